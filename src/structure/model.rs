//! The plate model of a design: mesh + planform + material + thicknesses, and its assembly.

use super::element::{self, Quad};
use super::mesh::PlateMesh;
use super::Orthotropic;
use crate::wing::{planform_point, DesignVector, Planform};
use faer::Mat;
use gustkit_core::scalar::{Dual, Scalar};
use std::sync::OnceLock;

/// Element stiffness and mass (row-major) with their derivatives along the four planform variables.
pub type ElementDuals = (Vec<Dual<4>>, Vec<Dual<4>>);

/// Values per node in a nodal field: (w, w_x, w_y, u, v).
pub const NODAL: usize = 5;

/// The two uncoupled fields of a flat plate at its mid-surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Field {
    /// Transverse deflection w and its slopes (DKQ): 3 DOFs a node.
    Bending,
    /// In-plane displacements (u, v): 2 DOFs a node.
    Membrane,
}

impl Field {
    pub const ALL: [Field; 2] = [Field::Bending, Field::Membrane];
    /// DOFs a node.
    pub fn dofs(self) -> usize {
        match self {
            Field::Bending => 3,
            Field::Membrane => 2,
        }
    }
    /// Offset of this field's values in a nodal [`NODAL`]-vector.
    pub fn nodal_offset(self) -> usize {
        match self {
            Field::Bending => 0,
            Field::Membrane => 3,
        }
    }
}

/// Why a plate model cannot be built.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ModelError {
    #[error("thickness[{index}]: must be positive and finite (got {value} m)")]
    Thickness { index: usize, value: f64 },
    #[error("thickness: expected {expected} design values for the mesh, got {got}")]
    ThicknessCount { expected: usize, got: usize },
    #[error("planform: {0}")]
    Planform(#[from] crate::wing::PlanformError),
    #[error("material: {0}")]
    Material(#[from] super::MaterialError),
    #[error("planform: element {0} is degenerate or inverted (the planform is crossed)")]
    Element(usize),
}

/// A plate model ready to assemble; cheap to build, holds no matrices.
#[derive(Clone, Debug)]
pub struct PlateModel {
    pub mesh: PlateMesh,
    pub material: Orthotropic,
    pub design: DesignVector,
    /// Equation number of each node's first DOF in each field, `None` where clamped.
    pub(crate) dof_start: [Vec<Option<usize>>; 2],
    pub(crate) n_dofs: [usize; 2],
    qbar: [[f64; 3]; 3],
    /// Element matrices with planform derivatives, per field, computed on first use by the
    /// sensitivities and shared by every reverse or forward product on this model.
    duals: [OnceLock<Vec<ElementDuals>>; 2],
}

impl PlateModel {
    /// Builds and checks a model.
    pub fn new(
        mesh: PlateMesh,
        material: Orthotropic,
        design: DesignVector,
    ) -> Result<Self, ModelError> {
        material.validate()?;
        design.planform.validate()?;
        if design.thickness.len() != mesh.n_dv() {
            return Err(ModelError::ThicknessCount {
                expected: mesh.n_dv(),
                got: design.thickness.len(),
            });
        }
        if let Some((index, &value)) = design
            .thickness
            .iter()
            .enumerate()
            .find(|(_, t)| !(**t > 0.0 && t.is_finite()))
        {
            return Err(ModelError::Thickness { index, value });
        }
        let mut dof_start = [Vec::new(), Vec::new()];
        let mut n_dofs = [0; 2];
        for f in Field::ALL {
            let k = f as usize;
            dof_start[k] = mesh
                .clamped
                .iter()
                .map(|&c| {
                    (!c).then(|| {
                        n_dofs[k] += f.dofs();
                        n_dofs[k] - f.dofs()
                    })
                })
                .collect();
        }
        let model = Self {
            qbar: material.qbar(),
            mesh,
            material,
            design,
            dof_start,
            n_dofs,
            duals: Default::default(),
        };
        let p = model.design.planform.to_array();
        for e in 0..model.mesh.elements.len() {
            if !element::is_valid(&model.element_xy(p, e)) {
                return Err(ModelError::Element(e));
            }
        }
        Ok(model)
    }

    pub fn planform(&self) -> &Planform {
        &self.design.planform
    }

    /// Free DOFs of a field.
    pub fn n_dofs(&self, field: Field) -> usize {
        self.n_dofs[field as usize]
    }

    /// Thickness of element e.
    pub fn element_thickness(&self, e: usize) -> f64 {
        self.design.thickness[self.mesh.element_dv[e]]
    }

    /// Physical corner coordinates of element e for planform variables p (generic for derivatives).
    pub fn element_xy<S: Scalar>(&self, p: [S; 4], e: usize) -> Quad<S> {
        self.mesh.elements[e].map(|n| {
            let [xi, eta] = self.mesh.nodes[n];
            planform_point(p, xi, eta)
        })
    }

    /// Physical coordinates of every node.
    pub fn node_xy(&self) -> Vec<[f64; 2]> {
        let p = self.design.planform.to_array();
        self.mesh
            .nodes
            .iter()
            .map(|&[xi, eta]| planform_point(p, xi, eta))
            .collect()
    }

    /// Global equation numbers of element e's local DOFs in a field (`None` where clamped).
    pub fn element_dofs(&self, field: Field, e: usize) -> Vec<Option<usize>> {
        let starts = &self.dof_start[field as usize];
        self.mesh.elements[e]
            .iter()
            .flat_map(|&n| (0..field.dofs()).map(move |d| starts[n].map(|s| s + d)))
            .collect()
    }

    /// Element stiffness and mass of a field for planform p and thickness t, as flat row-major
    /// n × n matrices (n = 12 bending, 8 membrane).
    pub fn element_matrices<S: Scalar>(
        &self,
        field: Field,
        p: [S; 4],
        e: usize,
        t: S,
    ) -> (Vec<S>, Vec<S>) {
        let xy = self.element_xy(p, e);
        let rho_t = t * self.material.density;
        match field {
            Field::Bending => {
                let d_unit = self.qbar.map(|r| r.map(|v| v / 12.0));
                let k = element::dkq_stiffness(&xy, &d_unit);
                let m = element::bending_mass(&xy);
                let t3 = t * t * t;
                (
                    k.iter().flatten().map(|&v| v * t3).collect(),
                    m.iter().flatten().map(|&v| v * rho_t).collect(),
                )
            }
            Field::Membrane => {
                let k = element::membrane_stiffness(&xy, &self.qbar);
                let m = element::membrane_mass(&xy);
                (
                    k.iter().flatten().map(|&v| v * t).collect(),
                    m.iter().flatten().map(|&v| v * rho_t).collect(),
                )
            }
        }
    }

    /// Element matrices of a field with their planform derivatives (see [`ElementDuals`]), at the
    /// current thicknesses; cached.
    pub fn element_duals(&self, field: Field) -> &[ElementDuals] {
        self.duals[field as usize].get_or_init(|| {
            let p = self.design.planform.to_array();
            let pd: [Dual<4>; 4] = std::array::from_fn(|k| Dual::var(p[k], k));
            (0..self.mesh.elements.len())
                .map(|e| self.element_matrices(field, pd, e, Dual::cst(self.element_thickness(e))))
                .collect()
        })
    }

    /// Dense stiffness and mass matrices of a field over its free DOFs.
    pub fn assemble(&self, field: Field) -> (Mat<f64>, Mat<f64>) {
        let n = self.n_dofs(field);
        let mut k = Mat::<f64>::zeros(n, n);
        let mut m = Mat::<f64>::zeros(n, n);
        let p = self.design.planform.to_array();
        for e in 0..self.mesh.elements.len() {
            let (ke, me) = self.element_matrices(field, p, e, self.element_thickness(e));
            let dofs = self.element_dofs(field, e);
            let nl = dofs.len();
            for (a, ga) in dofs.iter().enumerate() {
                let Some(ga) = *ga else { continue };
                for (b, gb) in dofs.iter().enumerate() {
                    let Some(gb) = *gb else { continue };
                    k[(ga, gb)] += ke[a * nl + b];
                    m[(ga, gb)] += me[a * nl + b];
                }
            }
        }
        (k, m)
    }

    /// Structural mass Σ ρ t_e A_e, kg.
    pub fn mass(&self) -> f64 {
        let p = self.design.planform.to_array();
        (0..self.mesh.elements.len())
            .map(|e| {
                self.material.density
                    * self.element_thickness(e)
                    * element::area(&self.element_xy(p, e))
            })
            .sum()
    }
}

/// Initial thickness of each design patch from the airfoil: local chord at the patch's mid-span
/// times z(ξa) + z(ξb) (see [`crate::wing::Airfoil::strip_thickness_ratio`]).
pub fn airfoil_thickness(
    mesh: &PlateMesh,
    planform: &Planform,
    airfoil: &crate::wing::Airfoil,
) -> Vec<f64> {
    (0..mesh.n_dv())
        .map(|dv| {
            let [[xa, xb], [ya, yb]] = mesh.dv_patch(dv);
            planform.chord(0.5 * (ya + yb)) * airfoil.strip_thickness_ratio(xa, xb)
        })
        .collect()
}
