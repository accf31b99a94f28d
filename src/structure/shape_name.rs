//! Names for mode shapes ("1st bending", "2nd torsion", "1st chordwise") by what the shape is.
//!
//! Every spanwise row of structural nodes is fitted, by least squares along its streamwise chord,
//! with a rigid section motion w = h + α (x − x̄): the heave h is bending, the pitch α torsion, the
//! remainder (curvature along the chord, a trailing-edge panel moving alone) chordwise or local.
//! The part holding at least [`DOMINANT`] of the shape's squared deflection names it; a shape that no
//! part dominates is called by its number ("mode 7") rather than by a wrong word.

use super::model::{Field, NODAL};
use super::{Modes, PlateModel};

/// Share of the squared deflection a part needs to name a mode.
pub const DOMINANT: f64 = 0.5;

/// How a mode's squared deflection splits between the three parts of the section fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShapeParts {
    /// Heave of the streamwise sections (spanwise bending).
    pub bending: f64,
    /// Pitch of the sections about their mid-chord (torsion).
    pub torsion: f64,
    /// What a rigid section motion leaves out (chordwise bending, local panel modes).
    pub chordwise: f64,
}

impl ShapeParts {
    /// The three shares (they sum to 1) of a bending-field mode shape.
    pub fn of(model: &PlateModel, shape: &[f64]) -> Self {
        let xy = model.node_xy();
        let row = model.mesh.nx + 1;
        let (mut heave, mut pitch, mut rest) = (0.0, 0.0, 0.0);
        for j in 0..=model.mesh.ny {
            let nodes = j * row..(j + 1) * row;
            let x: Vec<f64> = nodes.clone().map(|n| xy[n][0]).collect();
            let w: Vec<f64> = nodes.map(|n| shape[NODAL * n]).collect();
            let n = row as f64;
            let x_mean = x.iter().sum::<f64>() / n;
            let w_mean = w.iter().sum::<f64>() / n;
            let sxx: f64 = x.iter().map(|xi| (xi - x_mean).powi(2)).sum();
            let sxw: f64 = x.iter().zip(&w).map(|(xi, wi)| (xi - x_mean) * wi).sum();
            let alpha = if sxx > 0.0 { sxw / sxx } else { 0.0 };
            heave += n * w_mean * w_mean;
            pitch += alpha * alpha * sxx;
            rest += x
                .iter()
                .zip(&w)
                .map(|(xi, wi)| (wi - w_mean - alpha * (xi - x_mean)).powi(2))
                .sum::<f64>();
        }
        let total = (heave + pitch + rest).max(f64::MIN_POSITIVE);
        Self {
            bending: heave / total,
            torsion: pitch / total,
            chordwise: rest / total,
        }
    }

    /// The dominant part's word, or `None` when no part holds [`DOMINANT`] of the deflection.
    pub fn kind(&self) -> Option<usize> {
        [self.bending, self.torsion, self.chordwise]
            .iter()
            .position(|&share| share >= DOMINANT)
    }
}

/// English ordinal of n ≥ 1 ("1st", "2nd", "3rd", "4th", …, "11th", "21st").
fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

/// A name for each mode: "1st bending", "1st torsion", "1st chordwise" by [`ShapeParts`], numbered
/// in frequency order within each kind; in-plane (membrane) modes are "in-plane"; a mode that no part
/// dominates is "mode N" (its number in the basis).
pub fn mode_names(model: &PlateModel, modes: &Modes) -> Vec<String> {
    const WORDS: [&str; 4] = ["bending", "torsion", "chordwise", "in-plane"];
    let mut count = [0usize; 4];
    modes
        .modes
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let kind = match m.field {
                Field::Membrane => Some(3),
                Field::Bending => ShapeParts::of(model, &m.shape).kind(),
            };
            match kind {
                Some(k) => {
                    count[k] += 1;
                    format!("{} {}", ordinal(count[k]), WORDS[k])
                }
                None => format!("mode {}", i + 1),
            }
        })
        .collect()
}
