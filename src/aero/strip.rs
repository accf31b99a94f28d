//! The builders of Theodorsen/Sears strip theory: a 2-D section (the typical-section study) and
//! the wing as a sum of streamwise strips (`aero.fidelity: {"strip": …}`).

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

/// Strip theory on the wing, `aero.fidelity: {"strip": {...}}`: streamwise Theodorsen/Sears
/// sections at the centres of `n_strips` equal spanwise strips of the planform, each sampling
/// the modes at `points` chord points (the fit of its plunge and pitch). The classical
/// two-dimensional baseline: no downwash between strips, no tip loss, no sweep correction.
#[derive(Clone, Debug, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct StripWingSpec {
    #[serde(default = "default_strips")]
    pub n_strips: usize,
    #[serde(default = "default_points")]
    pub points: usize,
}

fn default_strips() -> usize {
    20
}

fn default_points() -> usize {
    11
}

/// The most strips (the model is a sum over them; beyond this nothing is resolved that the
/// lattice of a DLM would not resolve better).
pub const MAX_STRIPS: usize = 10_000;

impl StripWingSpec {
    /// The next resolution for the resolution check (twice the strips) and its words.
    pub fn refined(&self) -> (Self, String) {
        let s = Self {
            n_strips: 2 * self.n_strips,
            points: self.points,
        };
        let words = s.words();
        (s, words)
    }

    /// The model in words.
    pub fn words(&self) -> String {
        format!("strip theory, {} strips", self.n_strips)
    }

    /// The strips' stations on a planform: centre y, mid-chord x, semichord, width (m).
    fn stations(&self, p: &crate::wing::Planform) -> Vec<gustkit_core::strip::StripStation> {
        let a = p.to_array();
        let n = self.n_strips;
        (0..n)
            .map(|j| {
                let eta = (j as f64 + 0.5) / n as f64;
                let le = crate::wing::planform_point(a, 0.0, eta);
                let te = crate::wing::planform_point(a, 1.0, eta);
                gustkit_core::strip::StripStation {
                    y: le[1],
                    x_mid: 0.5 * (le[0] + te[0]),
                    b: 0.5 * (te[0] - le[0]),
                    width: p.span / n as f64,
                }
            })
            .collect()
    }
}

impl super::contract::WingBuilder for StripWingSpec {
    fn name(&self) -> &'static str {
        "strip"
    }

    /// The reverse mode covers the mode shapes; the strips do not move with the planform in it
    /// (no geometry derivatives).
    fn capabilities(&self) -> super::contract::Capabilities {
        super::contract::Capabilities {
            reverse: true,
            reverse_planform: false,
        }
    }

    fn validate(
        &self,
        _wing: &super::contract::WingContext,
    ) -> Result<(), super::contract::BuildError> {
        let fail = |path: &str, reason: String| super::contract::BuildError {
            path: path.into(),
            reason,
        };
        if !(1..=MAX_STRIPS).contains(&self.n_strips) {
            return Err(fail(
                "n_strips",
                format!("must lie in [1, {MAX_STRIPS}] (got {})", self.n_strips),
            ));
        }
        if !(2..=1000).contains(&self.points) {
            return Err(fail(
                "points",
                format!(
                    "must lie in [2, 1000]: two chord points fit a plunge and a pitch (got {})",
                    self.points
                ),
            ));
        }
        Ok(())
    }

    fn build(
        &self,
        wing: &super::contract::WingContext,
    ) -> Result<super::contract::WingFidelity, super::contract::BuildError> {
        self.validate(wing)?;
        let stations = self.stations(wing.planform);
        let model = gustkit_core::strip::StripWing::new(&stations, self.points);
        // each strip's chord points, in the model's order, at their (ξ, η) on the plate
        let n = self.points;
        let points = (0..self.n_strips)
            .flat_map(|j| {
                let eta = (j as f64 + 0.5) / self.n_strips as f64;
                (0..n).map(move |i| [i as f64 / (n - 1) as f64, eta])
            })
            .collect();
        Ok(super::contract::WingFidelity {
            model: Box::new(model),
            binding: super::contract::SurfaceBinding {
                points,
                geometry_jacobian: Vec::new(),
            },
        })
    }
}
