//! How every figure draws what a reader compares: series colours that all read on white, tick
//! labels without `-0` or `10.0`, and legends in a column or row of their own beside the plot,
//! so that no legend can cover data.

use anyhow::{anyhow, Result};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Series colours (Tableau 10 with the orange, pink, grey, olive and cyan darkened): each has a
/// contrast ratio of at least 3:1 against white (WCAG 2 graphics), and neighbours differ in hue.
const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (220, 105, 0),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (200, 100, 170),
    (110, 110, 110),
    (138, 139, 20),
    (18, 140, 155),
];

/// The colour of the i-th series (the palette repeats after ten: see [`series_dashed`]).
pub fn series_color(i: usize) -> RGBAColor {
    let (r, g, b) = PALETTE[i % PALETTE.len()];
    RGBColor(r, g, b).to_rgba()
}

/// Whether the i-th series is drawn dashed: the second round of the palette (series 11 to 20)
/// is, so that no two of the first twenty series look alike.
pub fn series_dashed(i: usize) -> bool {
    (i / PALETTE.len()) % 2 == 1
}

/// WCAG 2 contrast ratio of a colour against white.
pub fn contrast_on_white(c: RGBAColor) -> f64 {
    let lin = |v: u8| {
        let s = v as f64 / 255.0;
        if s <= 0.03928 {
            s / 12.92
        } else {
            ((s + 0.055) / 1.055).powf(2.4)
        }
    };
    let l = 0.2126 * lin(c.0) + 0.7152 * lin(c.1) + 0.0722 * lin(c.2);
    1.05 / (l + 0.05)
}

/// A tick label: the shortest decimal form to six significant digits, no trailing zeros (`10`,
/// `0.25`), zero never signed (a tick of −1e-17 is zero), exponents only for very large or small
/// numbers.
pub fn tick(v: &f64) -> String {
    let v = *v;
    if !v.is_finite() {
        return String::new();
    }
    if v.abs() < 1e-12 {
        return "0".into();
    }
    if v.abs() >= 1e6 || v.abs() < 1e-4 {
        let s = format!("{v:.3e}");
        let (mantissa, exp) = s.split_once('e').unwrap_or((&s, "0"));
        let mantissa = trim_zeros(mantissa);
        return format!("{mantissa}e{exp}");
    }
    let digits = (5 - v.abs().log10().floor() as i32).clamp(0, 10) as usize;
    trim_zeros(&format!("{v:.digits$}"))
}

fn trim_zeros(s: &str) -> String {
    if !s.contains('.') {
        return s.to_string();
    }
    let t = s.trim_end_matches('0').trim_end_matches('.');
    if t == "-0" {
        "0".into()
    } else {
        t.to_string()
    }
}

/// One legend entry: its label and colour, drawn as a line or, where `marker`, as a dot.
#[derive(Clone, Debug)]
pub struct LegendEntry {
    pub label: String,
    pub color: RGBAColor,
    pub marker: bool,
    /// A dashed line key (a series drawn dashed).
    pub dashed: bool,
}

impl LegendEntry {
    pub fn line(label: impl Into<String>, color: RGBAColor) -> Self {
        Self {
            label: label.into(),
            color,
            marker: false,
            dashed: false,
        }
    }
    pub fn marker(label: impl Into<String>, color: RGBAColor) -> Self {
        Self {
            marker: true,
            ..Self::line(label, color)
        }
    }
    /// The key of the i-th series of a figure (its colour, dashed where [`series_dashed`]).
    pub fn series(label: impl Into<String>, i: usize) -> Self {
        Self {
            dashed: series_dashed(i),
            ..Self::line(label, series_color(i))
        }
    }
}

const LEGEND_FONT: u32 = 14;
const LEGEND_ROW: i32 = 20;
const LEGEND_PAD: i32 = 8;
const LEGEND_KEY: i32 = 24;

/// Width in pixels the label takes at the legend's font (from the font's own layout).
fn label_width(label: &str) -> i32 {
    super::register_fonts();
    let font: FontDesc = ("sans-serif", LEGEND_FONT).into_font();
    font.box_size(label)
        .map_or(8 * label.len() as i32, |(w, _)| w as i32)
}

/// Width of a column of `entries` (key, gap, longest label, padding), capped at `max`.
fn column_width(entries: &[LegendEntry]) -> i32 {
    let longest = entries
        .iter()
        .map(|e| label_width(&e.label))
        .max()
        .unwrap_or(0);
    LEGEND_KEY + 6 + longest + 2 * LEGEND_PAD
}

/// Splits `area` into the plot's part and a legend column on its right, as wide as the entries
/// need (in as many columns as the height requires), and draws the legend there.
pub fn legend_right<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    top_offset: i32,
) -> Result<DrawingArea<DB, Shift>>
where
    DB::ErrorType: 'static,
{
    if entries.is_empty() {
        return Ok(area.clone());
    }
    let (w, h) = area.dim_in_pixel();
    let rows_fit = ((h as i32 - top_offset - 2 * LEGEND_PAD) / LEGEND_ROW).max(1) as usize;
    let cols = entries.len().div_ceil(rows_fit);
    let rows = entries.len().div_ceil(cols);
    let col_w = column_width(entries);
    let width = (cols as i32 * col_w).min(w as i32 / 2);
    let (plot, legend) = area.split_horizontally(w as i32 - width - 6);
    draw_legend(&legend, entries, cols, rows, col_w, (0, top_offset))?;
    Ok(plot)
}

/// Splits `area` into the plot's part and a legend band below it, one entry a row (or as many
/// to a row as fit the width), and draws the legend there.
pub fn legend_below<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
) -> Result<DrawingArea<DB, Shift>>
where
    DB::ErrorType: 'static,
{
    if entries.is_empty() {
        return Ok(area.clone());
    }
    let (w, h) = area.dim_in_pixel();
    let col_w = column_width(entries);
    let cols = ((w as i32 - 20) / col_w).clamp(1, entries.len() as i32) as usize;
    let rows = entries.len().div_ceil(cols);
    let height = rows as i32 * LEGEND_ROW + 2 * LEGEND_PAD + 6;
    let (plot, legend) = area.split_vertically(h as i32 - height);
    draw_legend(&legend, entries, cols, rows, col_w, (10, 4))?;
    Ok(plot)
}

/// The legend box (a white fill and a black frame) with the entries in `cols` columns of `rows`.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    cols: usize,
    rows: usize,
    col_w: i32,
    (x0, y0): (i32, i32),
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing a legend: {e}");
    let (w, _) = area.dim_in_pixel();
    let x1 = (x0 + cols as i32 * col_w).min(w as i32 - 1);
    let y1 = y0 + rows as i32 * LEGEND_ROW + 2 * LEGEND_PAD;
    area.draw(&Rectangle::new([(x0, y0), (x1, y1)], WHITE.filled()))
        .map_err(err)?;
    area.draw(&Rectangle::new([(x0, y0), (x1, y1)], BLACK.stroke_width(1)))
        .map_err(err)?;
    let font = ("sans-serif", LEGEND_FONT).into_font().color(&BLACK);
    for (i, e) in entries.iter().enumerate() {
        let (c, r) = (i / rows, i % rows);
        let x = x0 + LEGEND_PAD + c as i32 * col_w;
        let y = y0 + LEGEND_PAD + r as i32 * LEGEND_ROW + LEGEND_ROW / 2;
        if e.marker {
            area.draw(&Circle::new((x + LEGEND_KEY / 2, y), 4, e.color.filled()))
                .map_err(err)?;
        } else if e.dashed {
            for (a, b) in [(0, 8), (13, 21)] {
                area.draw(&PathElement::new(
                    vec![(x + a, y), (x + b, y)],
                    e.color.stroke_width(2),
                ))
                .map_err(err)?;
            }
        } else {
            area.draw(&PathElement::new(
                vec![(x, y), (x + LEGEND_KEY, y)],
                e.color.stroke_width(2),
            ))
            .map_err(err)?;
        }
        area.draw(&Text::new(
            e.label.clone(),
            (x + LEGEND_KEY + 6, y - LEGEND_FONT as i32 / 2 - 1),
            font.clone(),
        ))
        .map_err(err)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every series colour reads on white (contrast ≥ 3:1); plotters' Palette99 yellow did not
    /// (1.3:1).
    #[test]
    fn palette_reads_on_white() {
        for i in 0..PALETTE.len() {
            let c = contrast_on_white(series_color(i));
            assert!(c >= 3.0, "colour {i}: contrast {c:.2}");
        }
        let yellow = Palette99::pick(2).to_rgba();
        assert!(contrast_on_white(yellow) < 1.5);
    }

    /// The first twenty series differ in colour or line: the palette's second round is dashed.
    #[test]
    fn twenty_series_look_different() {
        let looks: Vec<(RGBAColor, bool)> = (0..20)
            .map(|i| (series_color(i), series_dashed(i)))
            .collect();
        for i in 0..20 {
            for j in i + 1..20 {
                assert!(looks[i] != looks[j], "series {i} and {j}");
            }
        }
    }

    /// Tick labels: no `-0`, no `10.0`, short decimals, exponents only at the extremes.
    #[test]
    fn tick_labels_are_short_and_never_negative_zero() {
        let cases = [
            (-0.0, "0"),
            (-1e-17, "0"),
            (10.0, "10"),
            (0.25, "0.25"),
            (0.1 + 0.2, "0.3"),
            (-0.005, "-0.005"),
            (172.8, "172.8"),
            (2.5e6, "2.5e6"),
            (3e-5, "3e-5"),
            (-0.0001, "-0.0001"),
            (1234.5678, "1234.57"),
        ];
        for (v, want) in cases {
            assert_eq!(tick(&v), want, "{v}");
        }
    }
}
