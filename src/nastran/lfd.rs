//! The LFD fidelity (Euler, linearized frequency domain) on a Nastran model: the built-in wing
//! mesh (or a mesh file) about the model's one CAERO1 panel of a half wing, its wall points
//! moved by the model's own splines, as the DLM's boxes are. The panel gives the planform; the
//! study gives the section (Nastran's panels are flat) and the reduced frequencies.

use super::aero::{modal_surface_on, modal_surface_vjp_on, spline_rows_at, LiftingSurfaces};
use super::bulk::BulkData;
use super::spline::SplineRows;
use super::structure::{RealModes, Structure};
use super::NastranError;
use crate::aero::{FidelitySpec, WingContext};
use crate::wing::{Airfoil, Planform};
use gustkit_core::{Aerodynamics, FlightCondition, ModalSurface};

type R<T> = Result<T, NastranError>;

/// The LFD model of a Nastran model's lifting surface with the splines' rows at its wall points.
pub struct NastranLfd {
    pub model: Box<dyn Aerodynamics>,
    /// The splines' rows at the wall points (their projections on the panel).
    pub rows: SplineRows,
    /// The panel's normal at each wall point (the direction its displacement is along).
    pub normals: Vec<[f64; 3]>,
    /// The wall points' projections on the panel, in the aerodynamic frame.
    pub points: Vec<[f64; 3]>,
    /// x of the panel's root leading edge in the aerodynamic frame: the mesh's origin.
    pub x_origin: f64,
    /// The Mach number the steady state was converged at.
    pub mach: f64,
    pub planform: Planform,
    /// Boxes whose points no spline moves (their wall points stay still).
    pub unmoved: Vec<u32>,
}

impl std::fmt::Debug for NastranLfd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NastranLfd")
            .field("wall_points", &self.points.len())
            .field("mach", &self.mach)
            .field("planform", &self.planform)
            .field("x_origin", &self.x_origin)
            .finish_non_exhaustive()
    }
}

impl NastranLfd {
    /// Builds the LFD of `spec` about the model's panel at `mach`, with `airfoil` as the
    /// section, and the splines' rows at its wall points. The model must be a half wing: one
    /// flat CAERO1 whose root edge lies on the symmetry plane of AERO's SYMXZ = 1 (the wing
    /// mesh's root is a symmetry plane).
    pub fn build(
        b: &BulkData,
        s: &Structure,
        surf: &LiftingSurfaces,
        (spec, airfoil): (&FidelitySpec, &Airfoil),
        flight: &FlightCondition,
        cache_dir: Option<&std::path::Path>,
    ) -> R<Self> {
        use gustkit_dlm::Symmetry;
        if !matches!(spec, FidelitySpec::Lfd(_)) {
            return Err(NastranError::model(
                "aero.fidelity",
                "a Nastran model takes the DLM from its own CAERO1 cards; the study's fidelity may only be \"lfd\"".into(),
            ));
        }
        let panels = &surf.dlm.surfaces;
        if panels.len() != 1 {
            return Err(NastranError::model(
                "CAERO1",
                format!("the LFD meshes a half wing of one CAERO1 panel; the model has {}: use the DLM for several surfaces", panels.len()),
            ));
        }
        if surf.dlm.symmetry != Symmetry::Symmetric {
            return Err(NastranError::model(
                "AERO",
                "the LFD's wing mesh has a symmetry plane at the root: give SYMXZ = 1 (a half wing with its mirror image)".into(),
            ));
        }
        let p = &panels[0];
        let what = p.name.clone();
        let scale = p.c1.abs().max(p.c4.abs());
        if p.p1[1].abs() > 1e-9 * scale {
            return Err(NastranError::model(
                &what,
                format!(
                    "its root edge lies at y = {} in the aerodynamic frame: the LFD's half wing starts on the symmetry plane y = 0",
                    p.p1[1]
                ),
            ));
        }
        if (p.p4[2] - p.p1[2]).abs() > 1e-9 * scale {
            return Err(NastranError::model(
                &what,
                "has dihedral (its root and tip edges lie at different z): the LFD's wing mesh is flat".into(),
            ));
        }
        let span = p.p4[1] - p.p1[1];
        let planform = Planform {
            span,
            sweep_c4: ((p.p4[0] + 0.25 * p.c4 - p.p1[0] - 0.25 * p.c1) / span).atan(),
            root_chord: p.c1,
            tip_chord: p.c4,
        };
        planform
            .validate()
            .map_err(|e| NastranError::model(&what, format!("as a planform: {e}")))?;
        let fail = |e: crate::aero::BuildError| {
            let path = if e.path.is_empty() {
                "aero.fidelity.lfd".to_string()
            } else {
                format!("aero.fidelity.lfd.{}", e.path)
            };
            NastranError::model(&path, e.reason)
        };
        let built = spec
            .builder()
            .build(&WingContext {
                planform: &planform,
                airfoil,
                flight,
                cache_dir,
                fixed_planform: true,
            })
            .map_err(fail)?;
        let x_origin = p.p1[0];
        let points: Vec<[f64; 3]> = built
            .binding
            .points
            .iter()
            .map(|&[xi, eta]| {
                let [x, y] = planform.point(xi, eta);
                [x + x_origin, y + p.p1[1], p.p1[2]]
            })
            .collect();
        let owners: Vec<usize> = points.iter().map(|q| owning_box(surf, *q)).collect();
        let (rows, unmoved) = spline_rows_at(b, s, surf, &points, &owners)?;
        let box_normals = &surf.dlm.surface().normals;
        let normals = owners.iter().map(|&o| box_normals[o]).collect();
        Ok(Self {
            model: built.model,
            rows,
            normals,
            points,
            x_origin,
            mach: flight.mach,
            planform,
            unmoved,
        })
    }

    /// The flight condition in the mesh's frame (the gust's reference x from the panel's root
    /// leading edge).
    pub fn flight(&self, flight: &FlightCondition) -> FlightCondition {
        FlightCondition {
            x_ref: flight.x_ref - self.x_origin,
            ..*flight
        }
    }

    /// The first `n_modes` modes on the wall points.
    pub fn modal_surface(&self, modes: &RealModes, n_modes: usize) -> ModalSurface {
        modal_surface_on(&self.normals, &self.rows, modes, n_modes)
    }

    /// The transpose of [`NastranLfd::modal_surface`]: seeds on the wall points to g-set seeds.
    pub fn modal_surface_vjp(&self, seed: &ModalSurface) -> faer::Mat<f64> {
        modal_surface_vjp_on(&self.normals, &self.rows, seed)
    }
}

/// The DLM box whose planform holds the point (aerodynamic frame, the panel's plane), or the
/// one whose centre is nearest (a point on the panel's edge, or just outside it by round-off).
fn owning_box(surf: &LiftingSurfaces, q: [f64; 3]) -> usize {
    let cross = |a: [f64; 3], b: [f64; 3], p: [f64; 3]| {
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
    };
    let boxes = &surf.dlm.boxes;
    for (i, bx) in boxes.iter().enumerate() {
        let c = bx.corners;
        let size = bx.chord.abs() + 2.0 * bx.e.abs();
        let tol = -1e-12 * size * size;
        let signs: Vec<f64> = (0..4).map(|k| cross(c[k], c[(k + 1) % 4], q)).collect();
        if signs.iter().all(|&v| v >= tol) || signs.iter().all(|&v| v <= -tol) {
            return i;
        }
    }
    let centre = |i: usize| {
        let c = boxes[i].corners;
        [
            0.25 * (c[0][0] + c[1][0] + c[2][0] + c[3][0]),
            0.25 * (c[0][1] + c[1][1] + c[2][1] + c[3][1]),
        ]
    };
    (0..boxes.len())
        .min_by(|&i, &j| {
            let d = |k: usize| {
                let c = centre(k);
                (c[0] - q[0]).powi(2) + (c[1] - q[1]).powi(2)
            };
            d(i).total_cmp(&d(j))
        })
        .expect("a panel has boxes")
}
