//! The builder contract every fidelity implements (the MPhys lesson: a builder per fidelity):
//! what a fidelity can do ([`Capabilities`]), what it is built for ([`WingContext`]), what it
//! gives back (a model and its [`SurfaceBinding`]: the plate points where it wants structural
//! displacements and how the planform variables move its geometry) and why it may refuse
//! ([`BuildError`]). The concrete builders ([`super::dlm`], [`super::lfd`], [`super::strip`])
//! depend on this file; only [`super::registry`] knows them all.

use crate::wing::{Airfoil, Planform, N_PLANFORM};
use gustkit_core::{Aerodynamics, FlightCondition};

/// What a fidelity can do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Capabilities {
    /// Reverse mode of the GAFs with respect to the mode shapes (adjoint gradients of the
    /// thickness variables, which act only through the modes).
    pub reverse: bool,
    /// The reverse mode also covers the planform variables (they move the model's geometry).
    pub reverse_planform: bool,
}

impl Capabilities {
    /// Refuses a use that needs gradients (`what`, e.g. "optimization") of a fidelity named
    /// `name` without a reverse mode; the reason names both.
    pub fn require_reverse(self, name: &str, what: &str) -> Result<(), String> {
        if self.reverse {
            Ok(())
        } else {
            Err(format!(
                "{what} needs adjoint gradients, and the {name} fidelity has no reverse mode"
            ))
        }
    }

    /// Refuses a use that needs the gradients of the planform variables from a fidelity whose
    /// reverse mode covers the mode shapes only.
    pub fn require_planform_reverse(self, name: &str, what: &str) -> Result<(), String> {
        self.require_reverse(name, what)?;
        if self.reverse_planform {
            Ok(())
        } else {
            Err(format!(
                "{what} needs the gradients of the planform variables (span, sweep_c4, root_chord, tip_chord), and the {name} fidelity's reverse mode covers the thickness variables only (its geometry does not move with the planform in the reverse mode); gustkit check-gradient --dv t[i] checks the thickness gradients"
            ))
        }
    }
}

/// Where a wing model wants structural displacements, and how the planform moves its geometry.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceBinding {
    /// For each point of the model's [`Aerodynamics::surface`], in its order, the point's (ξ, η)
    /// in the plate's parametrization: the model's points move with the planform.
    pub points: Vec<[f64; 2]>,
    /// ∂(geometry parameter)/∂(planform variable) for each of the model's geometry parameters
    /// (those its reverse mode differentiates, [`Aerodynamics::geometry_names`]).
    pub geometry_jacobian: Vec<[f64; N_PLANFORM]>,
}

/// One large allocation of a model, estimated from its spec: what it is, the field of the spec
/// that sizes it (a path inside the spec, as [`BuildError::path`]) and its bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelFootprint {
    pub what: String,
    pub path: String,
    pub bytes: f64,
}

/// What a model's memory depends on besides its spec.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sizing {
    /// Reduced frequencies of the GAF table.
    pub n_k: usize,
    /// Whether the reverse mode will run (its derivatives and the Jacobians they need).
    pub gradients: bool,
    /// The threads the model will run on (each frequency in flight holds its own solver state).
    pub threads: usize,
}

/// A wing model and its binding to the plate.
pub struct WingFidelity {
    pub model: Box<dyn Aerodynamics>,
    pub binding: SurfaceBinding,
}

/// A builder could not build its model: the JSON path of the field inside the fidelity's spec
/// (empty for the spec as a whole) and the reason. The caller knows where the spec lives in its
/// study file and names the whole path ([`BuildError::path_in`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{reason}")]
pub struct BuildError {
    pub path: String,
    pub reason: String,
}

impl BuildError {
    /// The JSON path of the field in a study whose fidelity spec sits at `spec_path`.
    pub fn path_in(&self, spec_path: &str) -> String {
        if self.path.is_empty() {
            spec_path.to_string()
        } else {
            format!("{spec_path}.{}", self.path)
        }
    }
}

/// What a wing fidelity is built for: the planform (SI), the section and the flight condition
/// (a CFD model converges its steady state there).
#[derive(Clone, Copy, Debug)]
pub struct WingContext<'a> {
    pub planform: &'a Planform,
    pub airfoil: &'a Airfoil,
    pub flight: &'a FlightCondition,
    /// Where the builder may keep state between runs (the run folder), if anywhere.
    pub cache_dir: Option<&'a std::path::Path>,
    /// The planform is not designed (a Nastran model's panel): the model need not carry the
    /// mesh's planform tangents, whose steady sensitivities its reverse mode would otherwise
    /// solve for.
    pub fixed_planform: bool,
}

/// A fidelity's builder for wing studies.
pub trait WingBuilder {
    /// The fidelity's name as the study file spells it.
    fn name(&self) -> &'static str;
    fn capabilities(&self) -> Capabilities;
    /// The Mach numbers this fidelity's theory holds for: why `mach` lies outside them (the
    /// caller names the field, `flight.mach`); any subsonic Mach number by default.
    fn check_mach(&self, _mach: f64) -> Result<(), String> {
        Ok(())
    }
    /// The model's largest allocation for these sizes, estimated from the spec before anything
    /// is built (the study adds it to its memory check); none by default. A model that checks
    /// its memory against a limit of its own spec (the LFD's `memory_limit_gb`, in `validate`)
    /// returns none; one whose size is known only once it is built (an external mesh) checks it
    /// in `build`.
    fn footprint(&self, _sizing: &Sizing) -> Option<ModelFootprint> {
        None
    }
    /// Cheap checks of the settings for a wing (sizes, memory estimates); builds nothing
    /// expensive.
    fn validate(&self, wing: &WingContext) -> Result<(), BuildError>;
    /// Cheap checks for a use with gradients (the reverse mode's memory, say); the default has
    /// nothing more to check.
    fn validate_gradients(&self, wing: &WingContext) -> Result<(), BuildError> {
        self.validate(wing)
    }
    /// The model of the wing, with its binding.
    fn build(&self, wing: &WingContext) -> Result<WingFidelity, BuildError>;
}
