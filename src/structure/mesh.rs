//! Structured plate mesh on the parametric (ξ, η) grid of the planform.

/// Which root nodes (η = 0) are clamped.
#[derive(Clone, Debug, PartialEq)]
pub enum Clamp {
    /// Every root node.
    All,
    /// Every root node but the leading- and trailing-edge ones (as one public AGARD model does).
    Interior,
    /// The listed chordwise node indices 0..=nx of the root row.
    Nodes(Vec<usize>),
}

/// A structured mesh of `nx × ny` quadrilaterals; design patch `(id, jd)` of a `dv_nx × dv_ny`
/// grid owns the `refine × refine` elements below it.
#[derive(Clone, Debug)]
pub struct PlateMesh {
    /// Elements chordwise and spanwise.
    pub nx: usize,
    pub ny: usize,
    /// Elements per design patch along each direction.
    pub refine: usize,
    /// Parametric coordinates (ξ, η) of each node; node (i, j) has index j (nx+1) + i.
    pub nodes: Vec<[f64; 2]>,
    /// Counter-clockwise corner nodes of each element; element (i, j) has index j nx + i.
    pub elements: Vec<[usize; 4]>,
    /// Thickness design variable of each element.
    pub element_dv: Vec<usize>,
    /// Whether each node is clamped (all DOFs fixed).
    pub clamped: Vec<bool>,
}

/// Why a mesh specification is unusable.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    #[error("chordwise and spanwise patch counts and the refinement must be at least 1")]
    Empty,
    #[error("clamp: root node index {0} is outside 0..={1}")]
    ClampIndex(usize, usize),
    #[error("clamp: no root node is clamped, the plate would be free")]
    NoClamp,
}

impl PlateMesh {
    /// Uniform mesh of `dv_nx × dv_ny` design patches each split into `refine²` elements.
    pub fn new(
        dv_nx: usize,
        dv_ny: usize,
        refine: usize,
        clamp: &Clamp,
    ) -> Result<Self, MeshError> {
        if dv_nx == 0 || dv_ny == 0 || refine == 0 {
            return Err(MeshError::Empty);
        }
        let (nx, ny) = (dv_nx * refine, dv_ny * refine);
        let mut nodes = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                nodes.push([i as f64 / nx as f64, j as f64 / ny as f64]);
            }
        }
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let mut elements = Vec::with_capacity(nx * ny);
        let mut element_dv = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                elements.push([id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
                element_dv.push((j / refine) * dv_nx + i / refine);
            }
        }
        let mut clamped = vec![false; nodes.len()];
        let root: Vec<usize> = match clamp {
            Clamp::All => (0..=nx).collect(),
            Clamp::Interior => (1..nx).collect(),
            Clamp::Nodes(list) => {
                if let Some(&bad) = list.iter().find(|&&i| i > nx) {
                    return Err(MeshError::ClampIndex(bad, nx));
                }
                list.clone()
            }
        };
        if root.is_empty() {
            return Err(MeshError::NoClamp);
        }
        for i in root {
            clamped[id(i, 0)] = true;
        }
        Ok(Self {
            nx,
            ny,
            refine,
            nodes,
            elements,
            element_dv,
            clamped,
        })
    }

    /// Number of thickness design variables.
    pub fn n_dv(&self) -> usize {
        (self.nx / self.refine) * (self.ny / self.refine)
    }

    /// Design patch grid (chordwise, spanwise).
    pub fn dv_grid(&self) -> (usize, usize) {
        (self.nx / self.refine, self.ny / self.refine)
    }

    /// Parametric extent [ξa, ξb] × [ηa, ηb] of thickness design patch `dv`.
    pub fn dv_patch(&self, dv: usize) -> [[f64; 2]; 2] {
        let (dnx, dny) = self.dv_grid();
        let (i, j) = (dv % dnx, dv / dnx);
        [
            [i as f64 / dnx as f64, (i + 1) as f64 / dnx as f64],
            [j as f64 / dny as f64, (j + 1) as f64 / dny as f64],
        ]
    }

    /// The element containing parametric point (ξ, η) and the natural coordinates inside it.
    pub fn locate(&self, xi: f64, eta: f64) -> (usize, [f64; 2]) {
        let fx = xi.clamp(0.0, 1.0) * self.nx as f64;
        let fy = eta.clamp(0.0, 1.0) * self.ny as f64;
        let i = (fx.floor() as usize).min(self.nx - 1);
        let j = (fy.floor() as usize).min(self.ny - 1);
        let e = j * self.nx + i;
        (
            e,
            [2.0 * (fx - i as f64) - 1.0, 2.0 * (fy - j as f64) - 1.0],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patches_and_location() {
        let m = PlateMesh::new(10, 10, 2, &Clamp::Interior).unwrap();
        assert_eq!((m.nx, m.ny), (20, 20));
        assert_eq!(m.n_dv(), 100);
        // every design patch owns exactly four elements
        let mut count = vec![0; 100];
        for &d in &m.element_dv {
            count[d] += 1;
        }
        assert!(count.iter().all(|&c| c == 4));
        // element (3, 5) lies in patch (1, 2)
        assert_eq!(m.element_dv[5 * 20 + 3], 2 * 10 + 1);
        assert_eq!(m.clamped.iter().filter(|&&c| c).count(), 19);
        let (e, nat) = m.locate(1.0, 1.0);
        assert_eq!(e, 20 * 20 - 1);
        assert_eq!(nat, [1.0, 1.0]);
        let (e, nat) = m.locate(0.075, 0.5);
        assert_eq!(e, 10 * 20 + 1);
        assert!((nat[0] - 0.0).abs() < 1e-12 && (nat[1] + 1.0).abs() < 1e-12);
        assert_eq!(m.dv_patch(11), [[0.1, 0.2], [0.1, 0.2]]);
    }

    #[test]
    fn bad_clamps_are_rejected() {
        assert_eq!(
            PlateMesh::new(2, 2, 1, &Clamp::Nodes(vec![5])).unwrap_err(),
            MeshError::ClampIndex(5, 2)
        );
        assert_eq!(
            PlateMesh::new(2, 2, 1, &Clamp::Nodes(vec![])).unwrap_err(),
            MeshError::NoClamp
        );
        assert_eq!(
            PlateMesh::new(0, 2, 1, &Clamp::All).unwrap_err(),
            MeshError::Empty
        );
    }
}
