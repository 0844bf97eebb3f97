//! The coupling pairs of the multirate step: every pair with a fast body at the micro nodes,
//! the nodes in vector lanes.

/// Nodes per vector of the coupling kernel.
pub(super) const LANES: usize = 8;

/// The pairs with a fast body at the micro nodes, the nodes in vector lanes: positions and
/// forces by coordinate (a row of `stride` nodes per coordinate, bodies in blocks of K).
pub(super) struct CouplingPairs<'a> {
    pub(super) g: f64,
    pub(super) slow_masses: &'a [f64],
    pub(super) fast_masses: &'a [f64],
    pub(super) stride: usize,
}

impl CouplingPairs<'_> {
    /// The forces of every fast–slow and fast–fast pair at the nodes `nodes` (whole vectors),
    /// added into `ff` (on the fast bodies) and, when given, `fs` (on the slow ones).
    pub(super) fn forces<const K: usize>(
        &self,
        xs: &[f64],
        xf: &[f64],
        mut fs: Option<&mut [f64]>,
        ff: &mut [f64],
        nodes: std::ops::Range<usize>,
    ) {
        let stride = self.stride;
        let lanes = |x: &[f64], body: usize, c: usize, first: usize| -> [f64; LANES] {
            let at = (body * K + c) * stride + first;
            std::array::from_fn(|l| x[at + l])
        };
        for first in nodes.step_by(LANES) {
            for (a, &ma) in self.fast_masses.iter().enumerate() {
                let xa: [[f64; LANES]; K] = std::array::from_fn(|c| lanes(xf, a, c, first));
                let mut acc = [[0.0f64; LANES]; K];
                let ga = self.g * ma;
                let mut pair = |xb: &[[f64; LANES]; K], gm: f64| {
                    let d: [[f64; LANES]; K] =
                        std::array::from_fn(|c| std::array::from_fn(|l| xb[c][l] - xa[c][l]));
                    let r2: [f64; LANES] =
                        std::array::from_fn(|l| (0..K).map(|c| d[c][l] * d[c][l]).sum());
                    let f: [f64; LANES] = std::array::from_fn(|l| gm / (r2[l] * r2[l].sqrt()));
                    let x: [[f64; LANES]; K] =
                        std::array::from_fn(|c| std::array::from_fn(|l| f[l] * d[c][l]));
                    for (acc, x) in acc.iter_mut().zip(&x) {
                        acc.iter_mut().zip(x).for_each(|(a, x)| *a += x);
                    }
                    x
                };
                for (s, &ms) in self.slow_masses.iter().enumerate() {
                    let xb: [[f64; LANES]; K] = std::array::from_fn(|c| lanes(xs, s, c, first));
                    let x = pair(&xb, ga * ms);
                    if let Some(fs) = fs.as_deref_mut() {
                        for (c, x) in x.iter().enumerate() {
                            let at = (s * K + c) * stride + first;
                            fs[at..at + LANES]
                                .iter_mut()
                                .zip(x)
                                .for_each(|(f, x)| *f -= x);
                        }
                    }
                }
                for (b, &mb) in self.fast_masses.iter().enumerate().skip(a + 1) {
                    let xb: [[f64; LANES]; K] = std::array::from_fn(|c| lanes(xf, b, c, first));
                    let x = pair(&xb, ga * mb);
                    for (c, x) in x.iter().enumerate() {
                        let at = (b * K + c) * stride + first;
                        ff[at..at + LANES]
                            .iter_mut()
                            .zip(x)
                            .for_each(|(f, x)| *f -= x);
                    }
                }
                for (c, acc) in acc.iter().enumerate() {
                    let at = (a * K + c) * stride + first;
                    ff[at..at + LANES]
                        .iter_mut()
                        .zip(acc)
                        .for_each(|(f, x)| *f += x);
                }
            }
        }
    }
}
