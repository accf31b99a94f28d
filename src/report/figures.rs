//! Figures of the structural model.

use super::{diverging, Figure};
use crate::structure::model::{Field, NODAL};
use crate::structure::{Modes, PlateModel};
use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Mode shapes on the planform: one panel a mode, each element coloured by its mean deflection
/// (membrane modes by in-plane displacement magnitude), scaled to the mode's maximum.
pub struct ModeShapes {
    /// Element corner polygons in display units.
    polygons: Vec<Vec<(f64, f64)>>,
    /// Per mode: title and per-element value in [-1, 1].
    panels: Vec<(String, Vec<f64>)>,
    unit: String,
}

impl ModeShapes {
    /// Builds the figure data; lengths are shown in `unit` (`to_m` metres each).
    pub fn new(model: &PlateModel, modes: &Modes, unit: &str, to_m: f64) -> Self {
        let xy = model.node_xy();
        let polygons = model
            .mesh
            .elements
            .iter()
            .map(|e| {
                e.iter()
                    .map(|&n| (xy[n][0] / to_m, xy[n][1] / to_m))
                    .collect()
            })
            .collect();
        let panels = modes
            .modes
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let value = |n: usize| {
                    let c = &m.shape[NODAL * n..NODAL * (n + 1)];
                    match m.field {
                        Field::Bending => c[0],
                        Field::Membrane => c[3].hypot(c[4]),
                    }
                };
                let vals: Vec<f64> = model
                    .mesh
                    .elements
                    .iter()
                    .map(|e| e.iter().map(|&n| value(n)).sum::<f64>() / 4.0)
                    .collect();
                let peak = vals
                    .iter()
                    .fold(0.0f64, |a, v| a.max(v.abs()))
                    .max(f64::MIN_POSITIVE);
                let kind = match m.field {
                    Field::Bending => "bending field",
                    Field::Membrane => "in-plane field",
                };
                (
                    format!("Mode {}: {:.2} Hz ({kind})", i + 1, m.freq_hz()),
                    vals.iter().map(|v| v / peak).collect(),
                )
            })
            .collect();
        Self {
            polygons,
            panels,
            unit: unit.to_string(),
        }
    }
}

impl Figure for ModeShapes {
    fn size(&self) -> (u32, u32) {
        let rows = self.panels.len().div_ceil(3).max(1) as u32;
        (1200, 420 * rows)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing mode shapes: {e}");
        area.fill(&WHITE).map_err(err)?;
        let rows = self.panels.len().div_ceil(3).max(1);
        let cells = area.split_evenly((rows, 3));
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for p in self.polygons.iter().flatten() {
            x0 = x0.min(p.0);
            x1 = x1.max(p.0);
            y0 = y0.min(p.1);
            y1 = y1.max(p.1);
        }
        // equal aspect: pad the shorter extent
        let (w, h) = (x1 - x0, y1 - y0);
        let half = 0.55 * w.max(h);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        for (cell, (title, vals)) in cells.iter().zip(&self.panels) {
            let mut chart = ChartBuilder::on(cell)
                .caption(title, ("sans-serif", 18))
                .margin(8)
                .x_label_area_size(30)
                .y_label_area_size(40)
                .build_cartesian_2d(cx - half..cx + half, cy - half..cy + half)
                .map_err(err)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(format!("x [{}]", self.unit))
                .y_desc(format!("y [{}]", self.unit))
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(err)?;
            chart
                .draw_series(
                    self.polygons
                        .iter()
                        .zip(vals)
                        .map(|(poly, v)| Polygon::new(poly.clone(), diverging(*v).filled())),
                )
                .map_err(err)?;
            chart
                .draw_series(self.polygons.iter().map(|poly| {
                    let mut closed = poly.clone();
                    closed.push(poly[0]);
                    PathElement::new(closed, BLACK.mix(0.25))
                }))
                .map_err(err)?;
        }
        Ok(())
    }
}
