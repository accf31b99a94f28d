//! Interpolation of GAF tables in reduced frequency: a not-a-knot cubic spline through the table's
//! k values. The interpolant is linear in the tabulated values, so it is stored as a weight matrix
//! (query × node) built once per grid: values Q(k) = Σ_i w_i(k) Q_i, and the reverse mode is its
//! transpose.

use faer::linalg::solvers::Solve;
use faer::Mat;

/// Spline weights of a set of query points over a set of nodes.
#[derive(Clone, Debug)]
pub struct SplineWeights {
    /// `weights[q][i]`: weight of node i in the value at query q.
    pub weights: Vec<Vec<f64>>,
}

impl SplineWeights {
    /// Not-a-knot cubic spline through `nodes` (strictly increasing, at least 4) evaluated at
    /// `queries` (inside [nodes₀, nodesₙ₋₁], or an error naming the first outside).
    pub fn new(nodes: &[f64], queries: &[f64]) -> Result<Self, String> {
        Ok(Self::with_slope(nodes, queries)?.0)
    }

    /// The weights and the weights of the spline's slope dQ/dk at the same queries.
    pub fn with_slope(nodes: &[f64], queries: &[f64]) -> Result<(Self, Self), String> {
        let basis = SplineBasis::new(nodes)?;
        let n = nodes.len();
        let mut weights = Vec::with_capacity(queries.len());
        let mut slopes = Vec::with_capacity(queries.len());
        for &k in queries {
            let (mut w, mut dw) = (vec![0.0; n], vec![0.0; n]);
            basis.weights_at(k, &mut w, &mut dw)?;
            weights.push(w);
            slopes.push(dw);
        }
        Ok((Self { weights }, Self { weights: slopes }))
    }
}

/// The not-a-knot spline of one node set, with the map from values to second derivatives
/// (M = B f) solved once, so that weights at many single queries (a p-k iteration's) cost
/// O(n) each.
#[derive(Clone, Debug)]
pub struct SplineBasis {
    nodes: Vec<f64>,
    h: Vec<f64>,
    b: Mat<f64>,
}

impl SplineBasis {
    /// The spline through `nodes` (strictly increasing, at least 4).
    pub fn new(nodes: &[f64]) -> Result<Self, String> {
        let n = nodes.len();
        if n < 4 {
            return Err(format!(
                "at least 4 reduced frequencies are needed for the spline, got {n}"
            ));
        }
        if nodes.windows(2).any(|w| !(w[1] > w[0])) {
            return Err("reduced frequencies must increase strictly".into());
        }
        let h: Vec<f64> = nodes.windows(2).map(|w| w[1] - w[0]).collect();
        // A M = R f for the second derivatives M
        let mut a = Mat::<f64>::zeros(n, n);
        let mut r = Mat::<f64>::zeros(n, n);
        a[(0, 0)] = h[1];
        a[(0, 1)] = -(h[0] + h[1]);
        a[(0, 2)] = h[0];
        a[(n - 1, n - 3)] = h[n - 2];
        a[(n - 1, n - 2)] = -(h[n - 3] + h[n - 2]);
        a[(n - 1, n - 1)] = h[n - 3];
        for i in 1..n - 1 {
            a[(i, i - 1)] = h[i - 1];
            a[(i, i)] = 2.0 * (h[i - 1] + h[i]);
            a[(i, i + 1)] = h[i];
            r[(i, i + 1)] += 6.0 / h[i];
            r[(i, i)] -= 6.0 / h[i] + 6.0 / h[i - 1];
            r[(i, i - 1)] += 6.0 / h[i - 1];
        }
        let b = a.partial_piv_lu().solve(&r); // M = B f
        Ok(Self {
            nodes: nodes.to_vec(),
            h,
            b,
        })
    }

    /// Writes the weights of the nodes in the value at `k` into `w` and in the slope dQ/dk into
    /// `dw` (both of the node count); `k` outside the nodes' range is an error naming it.
    pub fn weights_at(&self, k: f64, w: &mut [f64], dw: &mut [f64]) -> Result<(), String> {
        let (nodes, h, b) = (&self.nodes, &self.h, &self.b);
        let n = nodes.len();
        let (lo, hi) = (nodes[0], nodes[n - 1]);
        if !(k >= lo - 1e-12 * hi.abs() && k <= hi * (1.0 + 1e-12)) {
            return Err(format!(
                "k = {k} lies outside the GAF table [{lo}, {hi}]: extend the reduced frequencies or narrow the frequency grid"
            ));
        }
        let i = nodes.partition_point(|&x| x <= k).clamp(1, n - 1) - 1;
        let (hh, t) = (h[i], k - nodes[i]);
        let s = hh - t;
        let (ca, cb) = (s / hh, t / hh);
        let cm0 = s * s * s / (6.0 * hh) - hh * s / 6.0;
        let cm1 = t * t * t / (6.0 * hh) - hh * t / 6.0;
        // d/dk: ds/dk = −1, dt/dk = 1
        let (dca, dcb) = (-1.0 / hh, 1.0 / hh);
        let dcm0 = -s * s / (2.0 * hh) + hh / 6.0;
        let dcm1 = t * t / (2.0 * hh) - hh / 6.0;
        w.fill(0.0);
        dw.fill(0.0);
        w[i] += ca;
        w[i + 1] += cb;
        dw[i] += dca;
        dw[i + 1] += dcb;
        for j in 0..n {
            w[j] += cm0 * b[(i, j)] + cm1 * b[(i + 1, j)];
            dw[j] += dcm0 * b[(i, j)] + dcm1 * b[(i + 1, j)];
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Not-a-knot reproduces cubics exactly; it interpolates the nodes; a smooth function is
    /// approximated to O(h⁴).
    #[test]
    fn spline_reproduces_cubics_and_converges() {
        let nodes = [
            0.0, 0.02, 0.08, 0.18, 0.32, 0.5, 0.72, 0.98, 1.28, 1.62, 2.0,
        ];
        let cubic = |k: f64| 1.0 - 2.0 * k + 0.5 * k * k - 0.3 * k * k * k;
        let q: Vec<f64> = (0..=40).map(|i| 2.0 * i as f64 / 40.0).collect();
        let w = SplineWeights::new(&nodes, &q).unwrap();
        for (qi, wq) in q.iter().zip(&w.weights) {
            let v: f64 = wq.iter().zip(&nodes).map(|(a, k)| a * cubic(*k)).sum();
            assert!((v - cubic(*qi)).abs() < 1e-12, "{qi}");
        }
        let w = SplineWeights::new(&nodes, &nodes).unwrap();
        for (i, wq) in w.weights.iter().enumerate() {
            for (j, x) in wq.iter().enumerate() {
                assert!((x - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        let f = |k: f64| (1.3 * k).sin() / (1.0 + k);
        let err = |n: usize| {
            let nodes: Vec<f64> = (0..n).map(|i| 2.0 * i as f64 / (n - 1) as f64).collect();
            let q: Vec<f64> = (0..200).map(|i| 2.0 * (i as f64 + 0.5) / 200.0).collect();
            let w = SplineWeights::new(&nodes, &q).unwrap();
            q.iter()
                .zip(&w.weights)
                .map(|(k, wq)| {
                    (wq.iter().zip(&nodes).map(|(a, x)| a * f(*x)).sum::<f64>() - f(*k)).abs()
                })
                .fold(0.0, f64::max)
        };
        let (e1, e2) = (err(11), err(21));
        assert!(e1 / e2 > 10.0, "{e1} {e2}");
    }

    /// The slope weights are the derivative of the value weights: exact on a cubic, and equal to a
    /// Richardson-extrapolated central difference of the weights (inside one spline piece the
    /// weights are cubics, for which that difference is exact up to round-off).
    #[test]
    fn slope_weights_differentiate_the_spline() {
        let nodes = [
            0.0, 0.02, 0.08, 0.18, 0.32, 0.5, 0.72, 0.98, 1.28, 1.62, 2.0,
        ];
        let cubic = |k: f64| 1.0 - 2.0 * k + 0.5 * k * k - 0.3 * k * k * k;
        let dcubic = |k: f64| -2.0 + k - 0.9 * k * k;
        let q: Vec<f64> = (1..40).map(|i| 2.0 * i as f64 / 40.0 + 0.003).collect();
        let (_, d) = SplineWeights::with_slope(&nodes, &q).unwrap();
        for (qi, wq) in q.iter().zip(&d.weights) {
            let v: f64 = wq.iter().zip(&nodes).map(|(a, k)| a * cubic(*k)).sum();
            assert!((v - dcubic(*qi)).abs() < 1e-10, "{qi}: {v}");
        }
        let h = 1e-3;
        let central = |k: f64, h: f64, j: usize| {
            let p = SplineWeights::new(&nodes, &[k + h]).unwrap();
            let m = SplineWeights::new(&nodes, &[k - h]).unwrap();
            (p.weights[0][j] - m.weights[0][j]) / (2.0 * h)
        };
        for &k in &[0.05, 0.3, 1.1, 1.9] {
            let (_, d) = SplineWeights::with_slope(&nodes, &[k]).unwrap();
            for j in 0..nodes.len() {
                let fd = (4.0 * central(k, 0.5 * h, j) - central(k, h, j)) / 3.0;
                assert!((fd - d.weights[0][j]).abs() < 1e-9, "k {k} node {j}");
            }
        }
    }

    #[test]
    fn bad_grids_are_errors() {
        assert!(SplineWeights::new(&[0.0, 1.0, 2.0], &[0.5]).is_err());
        assert!(SplineWeights::new(&[0.0, 1.0, 1.0, 2.0], &[0.5]).is_err());
        let e = SplineWeights::new(&[0.0, 1.0, 2.0, 3.0], &[3.5]).unwrap_err();
        assert!(e.contains("outside"));
    }
}
