//! The discrete gust figures: the histories at each output's critical gusts and the peaks
//! against the gust gradient.

use super::discrete::{shown, DiscreteGustResults};
use super::figures::{line_plot, Panels, Series};
use super::FigureSink;
use crate::units::LengthUnit;
use anyhow::Result;

/// The figures: the histories at each output's critical gusts, and (1-cos) the peaks against H.
pub fn figures(
    d: &DiscreteGustResults,
    study: &str,
    unit: LengthUnit,
    sink: &mut impl FigureSink,
) -> Result<()> {
    let plots = d
        .outputs
        .iter()
        .map(|o| {
            let (_, u) = shown(unit, 1.0, &o.unit);
            let series: Vec<Series> = d
                .histories
                .iter()
                .filter(|h| h.output == o.name)
                .map(|h| {
                    let label = match h.gradient_ft {
                        Some(g) => format!("{} (H = {g:.0} ft)", h.gust),
                        None => h.gust.clone(),
                    };
                    let pts = h
                        .time_s
                        .iter()
                        .zip(&h.value)
                        .map(|(t, v)| (*t, shown(unit, *v, &h.unit).0))
                        .collect();
                    (label, pts)
                })
                .collect();
            line_plot(
                o.name.clone(),
                "t [s]",
                &format!("{} [{u}]", o.name),
                series,
            )
        })
        .collect();
    sink.figure(
        "discrete_gust_histories",
        &Panels {
            title: format!("{study}: discrete gust responses at the critical gusts"),
            cols: 2,
            plots,
        },
    )?;
    if d.profile != "tabulated" {
        let plots = d
            .outputs
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let (_, u) = shown(unit, 1.0, &o.unit);
                let max = d
                    .envelope
                    .iter()
                    .map(|e| (e.gradient_ft, shown(unit, e.max[i], &o.unit).0))
                    .collect();
                let min = d
                    .envelope
                    .iter()
                    .map(|e| (e.gradient_ft, shown(unit, e.min[i], &o.unit).0))
                    .collect();
                let mut p = line_plot(
                    o.name.clone(),
                    "gust gradient H [ft]",
                    &format!("peak {} [{u}]", o.name),
                    vec![("max".into(), max), ("min".into(), min)],
                );
                p.dotted = Vec::new();
                p
            })
            .collect();
        sink.figure(
            "discrete_gust_envelope",
            &Panels {
                title: format!("{study}: peaks against the 1-cos gust gradient"),
                cols: 2,
                plots,
            },
        )?;
    }
    Ok(())
}
