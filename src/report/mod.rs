//! Reports: figures (plotters, PNG and SVG), VTK files and markdown, always written atomically.

pub mod compare;
pub mod discrete;
pub mod discrete_plots;
pub mod figures;
pub mod folder;
pub mod results;
pub mod run;
pub mod style;
pub mod sweep;
pub mod text_boxes;
pub mod vtk;

use anyhow::{Context, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, then a rename, so a
/// reader never sees a half-written file and an earlier result survives a failed write.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create folder {}", dir.display()))?;
    if path.is_dir() {
        anyhow::bail!("{}: is a folder; give a file name", path.display());
    }
    crate::atomic::write(path, bytes).with_context(|| format!("cannot write {}", path.display()))
}

/// Writes a run's `results.json` (pretty JSON of `results`) and `summary.md`, atomically.
pub fn write_results(dir: &Path, results: &impl serde::Serialize, summary: &str) -> Result<()> {
    write_atomic(
        &dir.join("results.json"),
        serde_json::to_string_pretty(results)?.as_bytes(),
    )?;
    write_atomic(&dir.join("summary.md"), summary.as_bytes())
}

/// Reads and parses a JSON file; errors name the file.
pub fn read_json(path: &Path) -> Result<serde_json::Value> {
    let text =
        crate::study::read_text(path).with_context(|| format!("cannot read {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{}: not valid JSON", path.display()))
}

/// Deserializes JSON read from `path`; a value of the wrong shape is an error naming the file and
/// the JSON path of the offending field.
pub fn from_json<T: serde::de::DeserializeOwned>(
    path: &Path,
    value: &serde_json::Value,
) -> Result<T> {
    serde_path_to_error::deserialize(value)
        .map_err(|e| anyhow::anyhow!("{}: {}: {}", path.display(), e.path(), e.inner()))
}

/// Registers the embedded DejaVu Sans font with plotters once (no system font libraries needed).
pub(crate) fn register_fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // the embedded font is a valid TrueType file; a failure here would only lose text
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// Something that can draw itself on any plotters backend.
pub trait Figure {
    /// Pixel size of the figure.
    fn size(&self) -> (u32, u32);
    /// Draws onto `area`.
    fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static;
}

/// Where a report's figures go: files ([`FigureFiles`]) or, in tests, a check of what they draw.
pub trait FigureSink {
    fn figure(&mut self, stem: &str, fig: &impl Figure) -> Result<()>;
}

/// Figures saved as PNG and SVG in a folder ([`save_figure`]).
pub struct FigureFiles<'a>(pub &'a Path);

impl FigureSink for FigureFiles<'_> {
    fn figure(&mut self, stem: &str, fig: &impl Figure) -> Result<()> {
        save_figure(self.0, stem, fig)
    }
}

/// Saves a figure as `dir/stem.png` and `dir/stem.svg`, both atomically.
pub fn save_figure(dir: &Path, stem: &str, fig: &impl Figure) -> Result<()> {
    register_fonts();
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create folder {}", dir.display()))?;
    let size = fig.size();
    // PNG: render to a temporary .png (the encoder picks the format from the extension), then rename
    let tmp_png = dir.join(format!(".{stem}.tmp{}.png", std::process::id()));
    {
        let area = BitMapBackend::new(&tmp_png, size).into_drawing_area();
        fig.draw(&area)?;
        area.present()
            .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", tmp_png.display()))?;
    }
    let png = dir.join(format!("{stem}.png"));
    std::fs::rename(&tmp_png, &png)
        .with_context(|| format!("cannot move {} into place", png.display()))?;
    let mut svg = String::new();
    {
        let area = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        fig.draw(&area)?;
        area.present().map_err(|e| anyhow::anyhow!("svg: {e}"))?;
    }
    write_atomic(&dir.join(format!("{stem}.svg")), svg.as_bytes())
}

/// Diverging blue–white–red colour for v in [-1, 1].
pub fn diverging(v: f64) -> RGBColor {
    let v = v.clamp(-1.0, 1.0);
    let lerp = |a: f64, b: f64, t: f64| (a + (b - a) * t).round() as u8;
    if v >= 0.0 {
        RGBColor(
            lerp(255.0, 178.0, v),
            lerp(255.0, 24.0, v),
            lerp(255.0, 43.0, v),
        )
    } else {
        let t = -v;
        RGBColor(
            lerp(255.0, 33.0, t),
            lerp(255.0, 102.0, t),
            lerp(255.0, 172.0, t),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("gustkit-atomic-{}", std::process::id()));
        let p = dir.join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "two");
        let n = std::fs::read_dir(&dir).unwrap().count();
        assert_eq!(n, 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn unwritable_destination_is_an_error() {
        let e = write_atomic(Path::new("/proc/gustkit/x.txt"), b"x").unwrap_err();
        assert!(e.to_string().contains("cannot"), "{e}");
    }
}
