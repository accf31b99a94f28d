//! The builder of Theodorsen/Sears strip theory for a 2-D section.

use gustkit_core::strip::StripSection;

/// Strip theory on a section: the chord points where the rigid motion is fitted.
#[derive(Clone, Debug)]
pub struct StripSpec {
    pub points: usize,
}

impl Default for StripSpec {
    fn default() -> Self {
        Self { points: 41 }
    }
}

impl StripSpec {
    /// The model of a section of chord `chord_m`, mid-chord at x = 0.
    pub fn build(&self, chord_m: f64) -> StripSection {
        StripSection::new(0.5 * chord_m, 0.0, 1.0, self.points)
    }
}
