//! Figures of the structural model.

use super::results::{HistoryRow, OptimizationResults};
pub use super::results::{ModeShapes, PsdSeries};
use super::style::{legend_below, legend_right, series_color, series_dashed, tick, LegendEntry};
use super::{diverging, Figure};
use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

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
                .x_label_area_size(45)
                .y_label_area_size(58)
                .build_cartesian_2d(cx - half..cx + half, cy - half..cy + half)
                .map_err(err)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(format!("x [{}]", self.unit))
                .y_desc(format!("y [{}]", self.unit))
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 14))
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
        let curves = &self.result.curves;
        let entries: Vec<LegendEntry> = curves
            .iter()
            .enumerate()
            .map(|(i, c)| LegendEntry::series(format!("mode {}", c.mode), i))
            .collect();
        let plot = legend_right(area, &entries, 40)?;
        let (top, bottom) = plot.split_vertically(425);
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
        let clipped_any = curves
            .iter()
            .flat_map(|c| c.damping_g.iter())
            .any(|g| g.abs() > 1.0);
        for (panel, (ylo, yhi), ylabel, is_g) in [
            (
                &top,
                (gmin - pad, gmax + pad),
                if clipped_any {
                    "damping g (▲: beyond ±1, drawn at the edge)"
                } else {
                    "damping g"
                },
                true,
            ),
            (&bottom, (0.0, 1.05 * fmax), "frequency [Hz]", false),
        ] {
            let mut chart = ChartBuilder::on(panel)
                .caption(
                    if is_g { self.title.as_str() } else { "" },
                    ("sans-serif", 20),
                )
                .margin(10)
                .margin_right(30)
                .x_label_area_size(35)
                .y_label_area_size(60)
                .build_cartesian_2d(vmin..vmax, ylo..yhi)
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("velocity [m/s]")
                .y_desc(ylabel)
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 14))
                .draw()
                .map_err(err)?;
            for (i, c) in curves.iter().enumerate() {
                let color = series_color(i);
                let ys = if is_g { &c.damping_g } else { &c.frequency_hz };
                // dampings beyond the axis are drawn on its edge and marked by a triangle
                let clipped = |y: f64| y.clamp(ylo, yhi);
                if is_g {
                    chart
                        .draw_series(
                            c.velocity_m_s
                                .iter()
                                .zip(ys)
                                .filter(|(_, y)| **y < ylo || **y > yhi)
                                .map(|(v, y)| {
                                    TriangleMarker::new((*v, clipped(*y)), 5, color.filled())
                                }),
                        )
                        .map_err(err)?;
                }
                let pts = c
                    .velocity_m_s
                    .iter()
                    .cloned()
                    .zip(ys.iter().map(|y| clipped(*y)));
                if series_dashed(i) {
                    chart
                        .draw_series(DashedLineSeries::new(pts, 8, 5, color.stroke_width(2)))
                        .map_err(err)?;
                } else {
                    chart
                        .draw_series(LineSeries::new(pts, color.stroke_width(2)))
                        .map_err(err)?;
                }
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
        }
        Ok(())
    }
}

/// A unit squared as an axis label writes it: `m²`, but `(N m)²` for a compound unit.
fn squared_unit(unit: &str) -> String {
    if unit.contains(' ') {
        format!("({unit})²")
    } else {
        format!("{unit}²")
    }
}

/// Power spectral densities on log-log axes: one panel per entry, each with one or more series
/// of the same quantity.
pub struct PsdPlot {
    pub title: String,
    pub panels: Vec<Vec<PsdSeries>>,
}

impl Figure for PsdPlot {
    fn size(&self) -> (u32, u32) {
        (1000, 420 * self.panels.len().max(1) as u32)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing PSD: {e}");
        area.fill(&WHITE).map_err(err)?;
        let cells = area.split_evenly((self.panels.len().max(1), 1));
        for (i, (cell, series)) in cells.iter().zip(&self.panels).enumerate() {
            let entries: Vec<LegendEntry> = series
                .iter()
                .enumerate()
                .map(|(j, s)| LegendEntry::line(s.label.clone(), series_color(j)))
                .collect();
            let cell = &legend_right(cell, &entries, if i == 0 { 40 } else { 10 })?;
            let curves: Vec<Vec<(f64, f64)>> = series
                .iter()
                .map(|s| {
                    s.omega_rad_s
                        .iter()
                        .copied()
                        .zip(s.psd.iter().copied())
                        .filter(|(w, p)| *w > 0.0 && *p > 0.0)
                        .collect()
                })
                .collect();
            let all = || curves.iter().flatten();
            if all().next().is_none() {
                continue;
            }
            let w0 = all().map(|p| p.0).fold(f64::MAX, f64::min);
            let w1 = all().map(|p| p.0).fold(0.0, f64::max);
            let pmax = all().map(|p| p.1).fold(0.0, f64::max);
            let pmin = (pmax * 1e-10).max(all().map(|p| p.1).fold(f64::MAX, f64::min));
            let mut chart = ChartBuilder::on(cell)
                .caption(
                    if i == 0 { self.title.as_str() } else { "" },
                    ("sans-serif", 18),
                )
                .margin(10)
                .margin_right(30)
                .x_label_area_size(35)
                .y_label_area_size(70)
                .build_cartesian_2d((w0..w1).log_scale(), (pmin..pmax * 2.0).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("circular frequency [rad/s]")
                .y_desc(format!(
                    "PSD [{} s/rad]",
                    squared_unit(series.first().map_or("", |s| s.unit.as_str()))
                ))
                .x_label_formatter(&|v| format!("{v:.0e}"))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 14))
                .draw()
                .map_err(err)?;
            for (j, pts) in curves.iter().enumerate() {
                chart
                    .draw_series(LineSeries::new(
                        pts.iter().map(|p| (p.0, p.1.max(pmin))),
                        series_color(j).stroke_width(2),
                    ))
                    .map_err(err)?;
            }
        }
        Ok(())
    }
}

/// Convergence history of an optimization (like paper Fig. 6): objective and constraints against
/// iteration, each normalized by its reference (mass by the initial mass, RMS by its limit, area
/// by the initial area), with the feasible limit drawn; below it the KKT residual and the
/// constraint violation on a log axis (what says whether and how the run converged).
pub struct Convergence {
    title: String,
    /// (label, points) per curve.
    curves: Vec<(String, Vec<(f64, f64)>)>,
    /// (label, points) of the KKT residual and the violation (zeros are left out on the log axis).
    residuals: Vec<(String, Vec<(f64, f64)>)>,
}

impl Convergence {
    pub fn new(study: &str, o: &OptimizationResults) -> Self {
        let m0 = o.initial.mass_kg;
        let a0 = o.initial.area_m2;
        let it = |f: &dyn Fn(&HistoryRow) -> f64| {
            o.history
                .iter()
                .map(|h| (h.iteration as f64, f(h)))
                .collect::<Vec<_>>()
        };
        let mut curves = vec![
            ("mass / initial mass".to_string(), it(&|h| h.mass_kg / m0)),
            (
                format!("RMS {} / limit", o.output),
                it(&|h| h.rms_display / o.rms_limit),
            ),
        ];
        if o.fix_area {
            curves.push(("area / initial area".to_string(), it(&|h| h.area_m2 / a0)));
        }
        if let Some((factor, g_max)) = o.flutter_margin {
            let scale = o.damping_scale;
            if o.history.iter().all(|h| h.flutter_damping_peak.is_some()) {
                curves.push((
                    format!("largest p-k damping up to {factor} V: 1 + (g − g_max) / {scale}"),
                    it(&|h| 1.0 + (h.flutter_damping_peak.unwrap_or(g_max) - g_max) / scale),
                ));
            }
            curves.push((
                format!("its KS bound, the constraint: 1 + (g_KS − g_max) / {scale}"),
                it(&|h| 1.0 + (h.flutter_damping.unwrap_or(g_max) - g_max) / scale),
            ));
        }
        let residuals = vec![
            ("KKT residual".to_string(), it(&|h| h.kkt)),
            ("constraint violation".to_string(), it(&|h| h.violation)),
        ];
        Self {
            title: format!("{study}: optimization history"),
            curves,
            residuals,
        }
    }
}

impl Figure for Convergence {
    fn size(&self) -> (u32, u32) {
        (1000, 900)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing convergence: {e}");
        area.fill(&WHITE).map_err(err)?;
        let area = area.titled(&self.title, ("sans-serif", 20)).map_err(err)?;
        let (upper, lower) = area.split_vertically(560);
        let pts = || self.curves.iter().flat_map(|c| c.1.iter());
        let n = pts().map(|p| p.0).fold(1.0, f64::max);
        let ylo = pts().map(|p| p.1).fold(1.0, f64::min).min(0.9);
        let yhi = pts().map(|p| p.1).fold(1.0, f64::max).max(1.1);
        let pad = 0.05 * (yhi - ylo);
        // the constraints sit on 1 together at an optimum: wide pale lines under narrow dark
        // ones, with different markers, keep each visible where they coincide
        let width = |i: usize| {
            if i == 0 {
                2
            } else {
                2 + 2 * (self.curves.len() - i) as u32
            }
        };
        let entries: Vec<LegendEntry> = self
            .curves
            .iter()
            .enumerate()
            .map(|(i, c)| LegendEntry::line(c.0.clone(), series_color(i)))
            .collect();
        let plot = legend_below(&upper, &entries)?;
        let mut chart = ChartBuilder::on(&plot)
            .margin(12)
            .margin_right(30)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..n, ylo - pad..yhi + pad)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("iteration")
            .y_desc("normalized value")
            // integer iterations: at most one label per iteration
            .x_labels((n as usize).clamp(1, 10) + 1)
            .x_label_formatter(&|v| format!("{v:.0}"))
            .y_label_formatter(&tick)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 14))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(LineSeries::new(
                [(0.0, 1.0), (n, 1.0)],
                BLACK.mix(0.4).stroke_width(1),
            ))
            .map_err(err)?;
        for (i, (_, p)) in self.curves.iter().enumerate() {
            let color = series_color(i);
            let line = if i == 0 { color } else { color.mix(0.6) };
            chart
                .draw_series(LineSeries::new(
                    p.iter().copied(),
                    line.stroke_width(width(i)),
                ))
                .map_err(err)?;
            chart
                .draw_series(p.iter().map(|q| Circle::new(*q, 3, color.filled())))
                .map_err(err)?;
        }
        // KKT residual and violation
        let entries: Vec<LegendEntry> = self
            .residuals
            .iter()
            .enumerate()
            .map(|(i, c)| LegendEntry::line(c.0.clone(), series_color(i + 5)))
            .collect();
        let plot = legend_below(&lower, &entries)?;
        let positive = || {
            self.residuals
                .iter()
                .flat_map(|c| c.1.iter())
                .filter(|p| p.1 > 0.0 && p.1.is_finite())
        };
        let rlo = positive().map(|p| p.1).fold(f64::MAX, f64::min);
        let rhi = positive().map(|p| p.1).fold(0.0, f64::max);
        if rhi > 0.0 {
            let mut chart = ChartBuilder::on(&plot)
                .margin(12)
                .margin_right(30)
                .x_label_area_size(35)
                .y_label_area_size(60)
                .build_cartesian_2d(0.0..n, (rlo * 0.5..rhi * 2.0).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc("iteration")
                .y_desc("KKT residual, violation")
                .x_labels((n as usize).clamp(1, 10) + 1)
                .x_label_formatter(&|v| format!("{v:.0}"))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 14))
                .draw()
                .map_err(err)?;
            for (i, (_, p)) in self.residuals.iter().enumerate() {
                let color = series_color(i + 5);
                let kept: Vec<(f64, f64)> = p
                    .iter()
                    .copied()
                    .filter(|q| q.1 > 0.0 && q.1.is_finite())
                    .collect();
                chart
                    .draw_series(LineSeries::new(kept.iter().copied(), color.stroke_width(2)))
                    .map_err(err)?;
                chart
                    .draw_series(kept.iter().map(|q| Circle::new(*q, 2, color.filled())))
                    .map_err(err)?;
            }
        }
        Ok(())
    }
}

/// One thickness panel: title, element polygons, element thickness (display units).
pub type ThicknessPanel = (String, Vec<Vec<(f64, f64)>>, Vec<f64>);

/// Planforms coloured by element thickness on one common scale (like paper Fig. 7; flow from left
/// to right, x streamwise, y spanwise), with the scale's range in each caption.
pub struct ThicknessMaps {
    pub title: String,
    pub unit: String,
    pub panels: Vec<ThicknessPanel>,
}

/// Sequential white-to-dark-blue colour for v in [0, 1].
fn sequential(v: f64) -> RGBColor {
    let v = v.clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64| (a + (b - a) * v).round() as u8;
    RGBColor(lerp(247.0, 8.0), lerp(251.0, 48.0), lerp(255.0, 107.0))
}

impl Figure for ThicknessMaps {
    fn size(&self) -> (u32, u32) {
        (600 * self.panels.len().max(1) as u32, 620)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing thickness: {e}");
        area.fill(&WHITE).map_err(err)?;
        let area = area.titled(&self.title, ("sans-serif", 20)).map_err(err)?;
        let (body, bar) = area.split_vertically(540);
        let cells = body.split_evenly((1, self.panels.len().max(1)));
        let pts = || self.panels.iter().flat_map(|p| p.1.iter().flatten());
        let x0 = pts().map(|p| p.0).fold(f64::MAX, f64::min);
        let x1 = pts().map(|p| p.0).fold(f64::MIN, f64::max);
        let y0 = pts().map(|p| p.1).fold(f64::MAX, f64::min);
        let y1 = pts().map(|p| p.1).fold(f64::MIN, f64::max);
        let half = 0.55 * (x1 - x0).max(y1 - y0);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        let tmin = self
            .panels
            .iter()
            .flat_map(|p| p.2.iter())
            .fold(f64::MAX, |a, b| a.min(*b));
        let tmax = self
            .panels
            .iter()
            .flat_map(|p| p.2.iter())
            .fold(f64::MIN, |a, b| a.max(*b));
        let scale = |t: f64| (t - tmin) / (tmax - tmin).max(1e-300);
        for (cell, (title, polys, t)) in cells.iter().zip(&self.panels) {
            let mut chart = ChartBuilder::on(cell)
                .caption(title, ("sans-serif", 18))
                .margin(8)
                .x_label_area_size(45)
                .y_label_area_size(58)
                .build_cartesian_2d(cx - half..cx + half, cy - half..cy + half)
                .map_err(err)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(format!("x [{}] (flow →)", self.unit))
                .y_desc(format!("y [{}]", self.unit))
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 14))
                .draw()
                .map_err(err)?;
            chart
                .draw_series(
                    polys.iter().zip(t).map(|(poly, v)| {
                        Polygon::new(poly.clone(), sequential(scale(*v)).filled())
                    }),
                )
                .map_err(err)?;
            chart
                .draw_series(polys.iter().map(|poly| {
                    let mut closed = poly.clone();
                    closed.push(poly[0]);
                    PathElement::new(closed, BLACK.mix(0.3))
                }))
                .map_err(err)?;
        }
        // colour bar
        let mut chart = ChartBuilder::on(&bar)
            .margin_left(80)
            .margin_right(80)
            .margin_bottom(5)
            .x_label_area_size(30)
            .build_cartesian_2d(tmin..tmax.max(tmin + 1e-12), 0.0..1.0)
            .map_err(err)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .disable_y_axis()
            .x_desc(format!("element thickness [{}]", self.unit))
            .x_label_formatter(&tick)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 14))
            .draw()
            .map_err(err)?;
        let steps = 100;
        chart
            .draw_series((0..steps).map(|i| {
                let a = tmin + (tmax - tmin) * i as f64 / steps as f64;
                let b = tmin + (tmax - tmin) * (i + 1) as f64 / steps as f64;
                Rectangle::new([(a, 0.0), (b, 1.0)], sequential(scale(a)).filled())
            }))
            .map_err(err)?;
        Ok(())
    }
}

/// One curve of a [`LinePlot`]: label and (x, y) points.
pub type Series = (String, Vec<(f64, f64)>);

/// A plain x-y line plot (residual histories, lift histories, pressure distributions).
pub struct LinePlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    /// Logarithmic y axis (values ≤ 0 are left out).
    pub log_y: bool,
    /// Draw the y axis downwards (pressure coefficients).
    pub flip_y: bool,
    /// Series drawn as dots instead of lines (one that may lie on another line stays visible).
    pub dotted: Vec<usize>,
}

impl Figure for LinePlot {
    fn size(&self) -> (u32, u32) {
        (1000, 560)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing {}: {e}", self.title);
        area.fill(&WHITE).map_err(err)?;
        let keep =
            |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite() && (!self.log_y || p.1 > 0.0);
        let pts = || self.series.iter().flat_map(|s| s.1.iter().filter(keep));
        if pts().next().is_none() {
            return Ok(());
        }
        let (x0, x1) = (
            pts().map(|p| p.0).fold(f64::MAX, f64::min),
            pts().map(|p| p.0).fold(f64::MIN, f64::max),
        );
        let (y0, y1) = (
            pts().map(|p| p.1).fold(f64::MAX, f64::min),
            pts().map(|p| p.1).fold(f64::MIN, f64::max),
        );
        let x1 = if x1 > x0 { x1 } else { x0 + 1.0 };
        // markers at the ends of the x range would sit on the plot's border: a little room
        let x_pad = if self.dotted.is_empty() {
            0.0
        } else {
            0.03 * (x1 - x0)
        };
        let (x0, x1) = (x0 - x_pad, x1 + x_pad);
        let entries: Vec<LegendEntry> = self
            .series
            .iter()
            .enumerate()
            .map(|(i, (label, _))| {
                if self.dotted.contains(&i) {
                    LegendEntry::marker(label.clone(), series_color(i))
                } else {
                    LegendEntry::line(label.clone(), series_color(i))
                }
            })
            .collect();
        let area = &legend_right(area, &entries, 40)?;
        let mut chart = ChartBuilder::on(area);
        chart
            .caption(&self.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80);
        if self.log_y {
            let (lo, hi) = (y0 * 0.5, y1 * 2.0);
            let mut c = chart
                .build_cartesian_2d(x0..x1, (lo..hi).log_scale())
                .map_err(err)?;
            c.configure_mesh()
                .x_desc(self.x_label.as_str())
                .y_desc(self.y_label.as_str())
                .x_label_formatter(&tick)
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 14))
                .draw()
                .map_err(err)?;
            for (i, (_, p)) in self.series.iter().enumerate() {
                let color = series_color(i);
                if self.dotted.contains(&i) {
                    c.draw_series(
                        p.iter()
                            .filter(keep)
                            .map(|q| Circle::new(*q, 3, color.filled())),
                    )
                    .map_err(err)?;
                } else {
                    c.draw_series(LineSeries::new(
                        p.iter().filter(keep).copied(),
                        color.stroke_width(2),
                    ))
                    .map_err(err)?;
                }
            }
        } else {
            let pad = 0.05 * (y1 - y0).max(1e-12);
            let (lo, hi) = (y0 - pad, y1 + pad);
            let flip = self.flip_y;
            let f = move |y: f64| if flip { -y } else { y };
            let (blo, bhi) = if flip { (-hi, -lo) } else { (lo, hi) };
            let mut c = chart.build_cartesian_2d(x0..x1, blo..bhi).map_err(err)?;
            c.configure_mesh()
                .x_desc(self.x_label.as_str())
                .y_desc(self.y_label.as_str())
                .x_label_formatter(&tick)
                .y_label_formatter(&move |v| tick(&f(*v)))
                .label_style(("sans-serif", 14))
                .axis_desc_style(("sans-serif", 14))
                .draw()
                .map_err(err)?;
            for (i, (_, p)) in self.series.iter().enumerate() {
                let color = series_color(i);
                if self.dotted.contains(&i) {
                    c.draw_series(
                        p.iter()
                            .filter(keep)
                            .map(|q| Circle::new((q.0, f(q.1)), 3, color.filled())),
                    )
                    .map_err(err)?;
                } else {
                    c.draw_series(LineSeries::new(
                        p.iter().filter(keep).map(|q| (q.0, f(q.1))),
                        color.stroke_width(2),
                    ))
                    .map_err(err)?;
                }
            }
        }
        Ok(())
    }
}

/// Line plots in a grid of `cols` columns under one title.
pub struct Panels {
    pub title: String,
    pub cols: usize,
    pub plots: Vec<LinePlot>,
}

impl Figure for Panels {
    fn size(&self) -> (u32, u32) {
        let rows = self.plots.len().div_ceil(self.cols.max(1)).max(1) as u32;
        (760 * self.cols.max(1) as u32, 40 + 430 * rows)
    }

    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing {}: {e}", self.title);
        area.fill(&WHITE).map_err(err)?;
        let body = area.titled(&self.title, ("sans-serif", 20)).map_err(err)?;
        let rows = self.plots.len().div_ceil(self.cols.max(1)).max(1);
        for (cell, plot) in body
            .split_evenly((rows, self.cols.max(1)))
            .iter()
            .zip(&self.plots)
        {
            plot.draw(cell)?;
        }
        Ok(())
    }
}

pub fn line_plot(title: String, x_label: &str, y_label: &str, series: Vec<Series>) -> LinePlot {
    LinePlot {
        title,
        x_label: x_label.into(),
        y_label: y_label.into(),
        series,
        log_y: false,
        flip_y: false,
        dotted: Vec::new(),
    }
}

/// One GAF entry of a table at the i-th reduced frequency.
type GafEntry = Box<dyn Fn(&gustkit_core::GafTable, usize) -> num_complex::Complex64>;

/// GAFs of several tables of the same modes against k: the Q_ss diagonal and main couplings of
/// the first two modes and Q_gs of the first two, real and imaginary parts of each table.
pub fn gaf_panels(title: String, tables: &[(String, &gustkit_core::GafTable)]) -> Panels {
    let n = tables
        .first()
        .and_then(|t| t.1.q_gs.first())
        .map_or(0, |g| g.len());
    let mut entries: Vec<(String, GafEntry)> = Vec::new();
    for (m, l) in [(0, 0), (1, 1), (0, 1), (1, 0)] {
        if m < n && l < n {
            entries.push((
                format!("Q_ss[{}][{}]", m + 1, l + 1),
                Box::new(move |t: &gustkit_core::GafTable, i| t.q_ss[i][m][l]),
            ));
        }
    }
    for m in 0..n.min(2) {
        entries.push((
            format!("Q_gs[{}]", m + 1),
            Box::new(move |t: &gustkit_core::GafTable, i| t.q_gs[i][m]),
        ));
    }
    let plots = entries
        .iter()
        .map(|(name, get)| {
            let mut series = Vec::new();
            for (label, t) in tables {
                let pts = |part: &dyn Fn(num_complex::Complex64) -> f64| -> Vec<(f64, f64)> {
                    (0..t.k.len()).map(|i| (t.k[i], part(get(t, i)))).collect()
                };
                series.push((format!("Re, {label}"), pts(&|v| v.re)));
                series.push((format!("Im, {label}"), pts(&|v| v.im)));
            }
            line_plot(
                name.clone(),
                "reduced frequency k",
                "GAF (mass-normalized modes)",
                series,
            )
        })
        .collect();
    Panels {
        title,
        cols: 2,
        plots,
    }
}

/// (x, y) points of one curve.
type Points = Vec<(f64, f64)>;

/// The wall C_p of a steady LFD state at its root, mid-span and tip sections, from the CSV the
/// LFD fidelity writes beside the state (eta, x_c, side, cp): one panel a section, upper and lower
/// surface against x/c, the C_p axis downwards.
pub fn cp_sections(csv: &str) -> Result<Panels> {
    // (η as written, upper surface, lower surface)
    let mut sections: Vec<(String, Points, Points)> = Vec::new();
    for (i, line) in csv.lines().enumerate().skip(1) {
        let bad = || anyhow!("C_p sections, line {}: expected eta,x_c,side,cp", i + 1);
        let f: Vec<&str> = line.split(',').collect();
        let [eta, x, side, cp] = f[..] else {
            return Err(bad());
        };
        let (x, cp): (f64, f64) = (
            x.parse().map_err(|_| bad())?,
            cp.parse().map_err(|_| bad())?,
        );
        if sections.last().is_none_or(|s| s.0 != eta) {
            sections.push((eta.to_string(), Vec::new(), Vec::new()));
        }
        let s = sections.last_mut().expect("pushed");
        match side {
            "upper" => s.1.push((x, cp)),
            "lower" => s.2.push((x, cp)),
            _ => return Err(bad()),
        }
    }
    let plots = sections
        .into_iter()
        .map(|(eta, mut upper, mut lower)| {
            upper.sort_by(|a, b| a.0.total_cmp(&b.0));
            lower.sort_by(|a, b| a.0.total_cmp(&b.0));
            let eta: f64 = eta.parse().unwrap_or(f64::NAN);
            let mut plot = line_plot(
                format!("η = {eta:.3} (wall cells)"),
                "x/c",
                "C_p",
                vec![("upper".into(), upper), ("lower".into(), lower)],
            );
            plot.flip_y = true;
            // on a symmetric section at zero incidence the surfaces coincide: the lower one as
            // dots over the upper one's line keeps both visible
            plot.dotted = vec![1];
            plot
        })
        .collect();
    Ok(Panels {
        title: "Steady Euler C_p: root, mid-span and tip sections".into(),
        cols: 3,
        plots,
    })
}
