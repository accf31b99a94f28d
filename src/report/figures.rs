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

/// V-g and V-f diagrams of a p-k sweep, with the flutter point marked.
pub struct VgVf<'a> {
    pub result: &'a crate::flutter::FlutterResult,
    pub title: String,
}

impl Figure for VgVf<'_> {
    fn size(&self) -> (u32, u32) {
        (1100, 850)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing V-g/V-f: {e}");
        area.fill(&WHITE).map_err(err)?;
        let (top, bottom) = area.split_vertically(425);
        let curves = &self.result.curves;
        let vmin = curves
            .iter()
            .flat_map(|c| c.velocity_m_s.iter())
            .cloned()
            .fold(f64::MAX, f64::min);
        let vmax = curves
            .iter()
            .flat_map(|c| c.velocity_m_s.iter())
            .cloned()
            .fold(f64::MIN, f64::max);
        let gmin = curves
            .iter()
            .flat_map(|c| c.damping_g.iter())
            .cloned()
            .fold(0.0, f64::min)
            .max(-1.0);
        let gmax = curves
            .iter()
            .flat_map(|c| c.damping_g.iter())
            .cloned()
            .fold(0.0, f64::max)
            .min(1.0);
        let fmax = curves
            .iter()
            .flat_map(|c| c.frequency_hz.iter())
            .cloned()
            .fold(0.0, f64::max);
        let pad = 0.05 * (gmax - gmin).max(1e-3);
        for (panel, (ylo, yhi), ylabel, is_g) in [
            (&top, (gmin - pad, gmax + pad), "damping g", true),
            (&bottom, (0.0, 1.05 * fmax), "frequency [Hz]", false),
        ] {
            let mut chart = ChartBuilder::on(panel)
                .caption(
                    if is_g { self.title.as_str() } else { "" },
                    ("sans-serif", 20),
                )
                .margin(10)
                .x_label_area_size(35)
                .y_label_area_size(60)
                .build_cartesian_2d(vmin..vmax, ylo..yhi)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("velocity [m/s]")
                .y_desc(ylabel)
                .label_style(("sans-serif", 13))
                .draw()
                .map_err(err)?;
            for (i, c) in curves.iter().enumerate() {
                let color = Palette99::pick(i).to_rgba();
                let ys = if is_g { &c.damping_g } else { &c.frequency_hz };
                chart
                    .draw_series(LineSeries::new(
                        c.velocity_m_s.iter().cloned().zip(ys.iter().cloned()),
                        color.stroke_width(2),
                    ))
                    .map_err(err)?
                    .label(format!("mode {}", c.mode))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
                    });
            }
            if let (Some(v), Some(f)) = (
                self.result.flutter_speed_m_s,
                self.result.flutter_frequency_hz,
            ) {
                let y = if is_g { 0.0 } else { f };
                chart
                    .draw_series(std::iter::once(Circle::new((v, y), 6, BLACK.filled())))
                    .map_err(err)?;
            }
            if is_g {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 13))
                    .draw()
                    .map_err(err)?;
            }
        }
        Ok(())
    }
}

/// One PSD curve: label, unit, (ω rad/s, PSD) points.
pub type PsdCurve = (String, String, Vec<(f64, f64)>);

/// Power spectral densities of the gust response outputs on log-log axes.
pub struct PsdPlot {
    pub title: String,
    pub curves: Vec<PsdCurve>,
}

impl Figure for PsdPlot {
    fn size(&self) -> (u32, u32) {
        (1000, 420 * self.curves.len().max(1) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing PSD: {e}");
        area.fill(&WHITE).map_err(err)?;
        let panels = area.split_evenly((self.curves.len().max(1), 1));
        for (i, (panel, (label, unit, pts))) in panels.iter().zip(&self.curves).enumerate() {
            let pts: Vec<(f64, f64)> = pts
                .iter()
                .copied()
                .filter(|(w, p)| *w > 0.0 && *p > 0.0)
                .collect();
            if pts.is_empty() {
                continue;
            }
            let (w0, w1) = (pts[0].0, pts[pts.len() - 1].0);
            let pmax = pts.iter().map(|p| p.1).fold(0.0, f64::max);
            let pmin = (pmax * 1e-10).max(pts.iter().map(|p| p.1).fold(f64::MAX, f64::min));
            let mut chart = ChartBuilder::on(panel)
                .caption(
                    if i == 0 { self.title.as_str() } else { "" },
                    ("sans-serif", 18),
                )
                .margin(10)
                .x_label_area_size(35)
                .y_label_area_size(70)
                .build_cartesian_2d((w0..w1).log_scale(), (pmin..pmax * 2.0).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("circular frequency [rad/s]")
                .y_desc(format!("PSD of {label} [{unit}² s/rad]"))
                .x_label_formatter(&|v| format!("{v:.0e}"))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style(("sans-serif", 12))
                .draw()
                .map_err(err)?;
            chart
                .draw_series(LineSeries::new(
                    pts.iter().map(|p| (p.0, p.1.max(pmin))),
                    BLUE.stroke_width(2),
                ))
                .map_err(err)?;
        }
        Ok(())
    }
}
