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

/// Collects the legend boxes that hide or cut plotted data in every figure a report renders.
#[derive(Default)]
struct Covered(Vec<(String, [i32; 4], (i32, i32))>);

impl FigureSink for Covered {
    fn figure(&mut self, stem: &str, fig: &impl Figure) -> anyhow::Result<()> {
        for (r, p) in gustkit::report::text_boxes::legends_over_data(fig)? {
            self.0.push((stem.to_string(), r, p));
        }
        Ok(())
    }
}

/// No legend covers data: legends sit in a column or band of their own beside the plot. Before
/// this, plotters' in-plot legends covered the V-g curves where g crosses 0, the sweep's points
/// and the fidelities' GAF curves.
#[test]
fn report_legends_cover_no_data() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut found = Covered::default();
    let mut legends = 0;
    for run in [
        "reports/reference/agard445_dlm",
        "reports/reference/agard445_lfd_analysis",
    ] {
        let path = root.join(run).join("results.json");
        let value: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let r = gustkit::report::run::read(&path, &value).unwrap();
        gustkit::report::run::figures(&r, &mut found).unwrap();
        struct Count<'a>(&'a mut usize);
        impl FigureSink for Count<'_> {
            fn figure(&mut self, _: &str, fig: &impl Figure) -> anyhow::Result<()> {
                *self.0 += gustkit::report::text_boxes::drawn(fig)?.legends.len();
                Ok(())
            }
        }
        gustkit::report::run::figures(&r, &mut Count(&mut legends)).unwrap();
    }
    for (stem, r, p) in &found.0 {
        println!("{stem}: legend {r:?} over data at {p:?}");
    }
    // the check sees the legends it is about
    assert!(legends >= 5, "{legends} legends found");
    assert!(found.0.is_empty(), "{} marks under legends", found.0.len());
}

/// The detector itself: plotters' own in-plot legend (what the figures used before) drawn over a
/// curve that runs under it is found; the same curve with the legend beside the plot is not.
#[test]
fn legend_detector_finds_an_in_plot_legend() {
    use plotters::coord::Shift;
    use plotters::prelude::*;
    struct Plot(bool);
    impl Figure for Plot {
        fn size(&self) -> (u32, u32) {
            (600, 400)
        }
        fn draw<DB: DrawingBackend>(&self, area: &DrawingArea<DB, Shift>) -> anyhow::Result<()>
        where
            DB::ErrorType: 'static,
        {
            let e = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("{e}");
            area.fill(&WHITE).map_err(e)?;
            let entries = [gustkit::report::style::LegendEntry::line(
                "a curve",
                gustkit::report::style::series_color(0),
            )];
            let plot = if self.0 {
                area.clone()
            } else {
                gustkit::report::style::legend_right(area, &entries, 10)?
            };
            let mut c = ChartBuilder::on(&plot)
                .margin(10)
                .build_cartesian_2d(0.0..1.0, 0.0..1.0)
                .map_err(e)?;
            c.draw_series(LineSeries::new(
                (0..=100).map(|i| (i as f64 / 100.0, 0.95)),
                BLUE.stroke_width(2),
            ))
            .map_err(e)?
            .label("a curve")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLUE));
            if self.0 {
                c.configure_series_labels()
                    .position(SeriesLabelPosition::UpperRight)
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()
                    .map_err(e)?;
            }
            Ok(())
        }
    }
    let over = gustkit::report::text_boxes::legends_over_data(&Plot(true)).unwrap();
    assert!(
        !over.is_empty(),
        "the in-plot legend over the curve was not found"
    );
    let beside = gustkit::report::text_boxes::legends_over_data(&Plot(false)).unwrap();
    assert!(beside.is_empty(), "{beside:?}");
}
