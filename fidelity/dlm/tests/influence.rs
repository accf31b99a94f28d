//! The influence matrices as assembled (sending boxes strip by strip, the kernel at a line end
//! shared by spanwise neighbours evaluated once) against the pair-by-pair sums of the steady and
//! oscillatory influences of every box and its image.

use gustkit_dlm::cplx::Cplx;
use gustkit_dlm::influence::{oscillatory_influences, steady_influence};
use gustkit_dlm::{Dlm, Spacing, SurfaceSpec, Symmetry};

fn surface(
    name: &str,
    p1: [f64; 3],
    p4: [f64; 3],
    chords: (f64, f64),
    n: (usize, usize),
) -> SurfaceSpec {
    SurfaceSpec {
        name: name.into(),
        p1,
        c1: chords.0,
        p4,
        c4: chords.1,
        n_chord: n.0,
        n_span: n.1,
        chord_spacing: Spacing::Uniform,
        span_spacing: Spacing::Cosine,
    }
}

/// A swept, tapered wing and a tail with dihedral above its plane (non-planar pairs, kernel
/// points upstream, downstream and on a line's axis), with and without the mirror image: every
/// entry equals the direct sum to 1e-13 of the largest (both are the same formulas; only the
/// line ends' arithmetic and the order of the roundings differ).
#[test]
fn shared_line_ends_equal_pair_by_pair_sums() {
    let wing = surface(
        "wing",
        [0.0, 0.0, 0.0],
        [0.8, 0.76, 0.0],
        (0.56, 0.37),
        (3, 5),
    );
    let tail = surface(
        "tail",
        [1.6, 0.0, 0.1],
        [1.9, 0.35, 0.25],
        (0.3, 0.2),
        (2, 3),
    );
    let kds = [0.0, 0.4, 2.5, 9.0];
    let mach = 0.6;
    for symmetry in [Symmetry::None, Symmetry::Symmetric, Symmetry::Antisymmetric] {
        let dlm = Dlm::new(vec![wing.clone(), tail.clone()], symmetry).unwrap();
        let n = dlm.n_boxes();
        let mats = dlm.influence_matrices(&dlm.boxes, mach, &kds);
        let sign = match symmetry {
            Symmetry::None => None,
            Symmetry::Symmetric => Some(1.0),
            Symmetry::Antisymmetric => Some(-1.0),
        };
        let mut osc = vec![Cplx::<f64>::zero(); kds.len()];
        let mut osc_img = vec![Cplx::<f64>::zero(); kds.len()];
        let mut worst: f64 = 0.0;
        let mut biggest: f64 = 0.0;
        for r in 0..n {
            let rb = &dlm.boxes[r];
            for s in 0..n {
                let sb = &dlm.boxes[s];
                let mut steady = steady_influence(rb, sb, mach);
                oscillatory_influences(rb, sb, mach, &kds, &mut osc);
                if let Some(sg) = sign {
                    let img = sb.mirrored();
                    steady += steady_influence(rb, &img, mach) * sg;
                    oscillatory_influences(rb, &img, mach, &kds, &mut osc_img);
                    for (o, i) in osc.iter_mut().zip(&osc_img) {
                        *o = *o + i.scale_f(sg);
                    }
                }
                for (k, o) in osc.iter().enumerate() {
                    let direct = (Cplx::real(steady) + *o).value();
                    let assembled = mats[k][r * n + s].value();
                    worst = worst.max((direct - assembled).norm());
                    biggest = biggest.max(direct.norm());
                }
            }
        }
        assert!(
            worst <= 1e-13 * biggest,
            "{symmetry:?}: largest difference {worst:e} of {biggest:e}"
        );
    }
}
