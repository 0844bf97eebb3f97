// The textbook enrichment, shared by the library's unit tests (src/basis/enriched/tests.rs)
// and its integration tests (tests/enriched.rs): the negative control of the conditioning
// tests. It is `include!`d into a module that has brought `Basis` and `Legendre` into scope
// (`crate::basis` inside the library, `galerkin_vi::basis` outside), so one copy serves both.
//
// sin(θτ) − τ sin θ and cos(θτ) − (1 − τ) − τ cos θ beside the Legendre functions of degree
// ≤ p: the space P_p ⊕ span{sin θτ, cos θτ} of `Enriched::new(p, θ, 1)`, with the
// representatives that become nearly polynomial as θ → 0 (docs/guide/enriched-bases.md,
// "Conditioning as ωh → 0").

/// The textbook enriched basis: p + 3 functions, trigonometric frequency θ in τ.
#[derive(Debug)]
pub struct NaiveEnriched {
    legendre: Legendre,
    p: usize,
    theta: f64,
}

impl NaiveEnriched {
    /// Degree p ≥ 1 polynomials plus the textbook sin/cos of frequency θ in τ.
    pub fn new(p: usize, theta: f64) -> Self {
        let legendre = match Legendre::new(p + 1) {
            Ok(l) => l,
            Err(e) => panic!("Legendre({}) for the naive enrichment: {e}", p + 1),
        };
        NaiveEnriched { legendre, p, theta }
    }
}

impl Basis for NaiveEnriched {
    fn len(&self) -> usize {
        self.p + 3
    }
    fn name(&self) -> &'static str {
        "naive-enriched"
    }
    fn eval(&self, tau: f64, values: &mut [f64], derivatives: &mut [f64]) {
        let (p, th) = (self.p, self.theta);
        self.legendre
            .eval(tau, &mut values[..=p], &mut derivatives[..=p]);
        values[p + 2] = values[p];
        derivatives[p + 2] = derivatives[p];
        let (s, c) = (th * tau).sin_cos();
        let (s1, c1) = th.sin_cos();
        values[p] = s - tau * s1;
        derivatives[p] = th * c - s1;
        values[p + 1] = c - (1.0 - tau) - tau * c1;
        derivatives[p + 1] = -th * s + 1.0 - c1;
    }
    fn polynomial_degree(&self) -> Option<usize> {
        None
    }
}
