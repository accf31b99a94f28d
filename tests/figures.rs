//! What a report's figures draw, checked without looking at pixels: no title, axis label, tick
//! label or legend text may be drawn over another (the boxes come from the same font layout,
//! anchor and rotation the PNG and SVG backends use).

use gustkit::report::text_boxes::{overlapping_text, TextBox};
use gustkit::report::{Figure, FigureSink};
use std::path::Path;

/// Collects the overlapping texts of every figure a report renders.
#[derive(Default)]
struct Overlaps(Vec<(String, TextBox, TextBox)>);

impl FigureSink for Overlaps {
    fn figure(&mut self, stem: &str, fig: &impl Figure) -> anyhow::Result<()> {
        // no slack: boxes that touch by a pixel read as one line of text
        for (a, b) in overlapping_text(fig, 0)? {
            self.0.push((stem.to_string(), a, b));
        }
        Ok(())
    }
}

/// Every figure of two reference reports draws no text over other text: the flagship (modes, gust
/// PSDs, convergence, thickness maps) and the LFD analysis (the GAFs and PSDs of the two
/// fidelities side by side). Before this check the modes and thickness figures failed it (the
/// axis titles sat on the tick labels "15.0", "20.0" and "25.0").
#[test]
fn report_figures_draw_no_text_over_text() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Overlaps::default();
    for run in [
        "reports/reference/agard445_dlm",
        "reports/reference/agard445_lfd_analysis",
    ] {
        let path = root.join(run).join("results.json");
        let value: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let r = gustkit::report::run::read(&path, &value).unwrap();
        gustkit::report::run::figures(&r, &mut found).unwrap();
    }
    for (stem, a, b) in &found.0 {
        println!(
            "{stem}: {:?} {:?} over {:?} {:?}",
            a.text, a.rect, b.text, b.rect
        );
    }
    assert!(found.0.is_empty(), "{} overlapping texts", found.0.len());
}
