//! Jacobi coordinates of an N-body system and the Wisdom–Holman splitting of its Hamiltonian
//! into Kepler motions and their interaction (Wisdom & Holman 1991; the choice of Kepler masses
//! of REBOUND's WHFast, Rein & Tamayo 2015).
//!
//! With interior masses ηᵢ = m₀ + … + mᵢ and Rᵢ the centre of mass of bodies 0 … i, the Jacobi
//! positions are r′ᵢ = rᵢ − Rᵢ₋₁ (i ≥ 1) and r′₀ = R_{N−1}. Their momenta are the covector
//! transform p′ = (∂r/∂r′)ᵀ p: p′ᵢ = (ηᵢ₋₁ pᵢ − mᵢ Σ_{j<i} pⱼ)/ηᵢ = m′ᵢ (vᵢ − Vᵢ₋₁) with the
//! Jacobi masses m′ᵢ = mᵢ ηᵢ₋₁/ηᵢ, and p′₀ the total momentum. The point transformation is
//! canonical, so the Hamiltonian H = Σ |pᵢ|²/2mᵢ − Σ_{i<j} G mᵢ mⱼ/|rᵢ − rⱼ| reads
//!
//! H = |p′₀|²/2η_{N−1} + Σ_{i≥1} [ |p′ᵢ|²/2m′ᵢ − G m′ᵢ ηᵢ/|r′ᵢ| ] + H_I(r′),
//! H_I = Σ_{i≥1} G m′ᵢ ηᵢ/|r′ᵢ| − Σ_{i<j} G mᵢ mⱼ/|rᵢ − rⱼ|:
//!
//! a free drift of the centre of mass, one Kepler problem per Jacobi body (gravitational
//! parameter μᵢ = G ηᵢ) and an interaction H_I that depends on positions only and is of the
//! order of the planet-to-star mass ratio.

/// The masses of the splitting and the linear maps between Cartesian and Jacobi coordinates.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Jacobi {
    /// mᵢ.
    masses: Vec<f64>,
    /// ηᵢ = m₀ + … + mᵢ.
    eta: Vec<f64>,
    /// m′ᵢ = mᵢ ηᵢ₋₁/ηᵢ for i ≥ 1; m′₀ = η_{N−1} (the total mass).
    jacobi_masses: Vec<f64>,
    /// μᵢ = G ηᵢ for i ≥ 1 (μ₀ unused).
    mu: Vec<f64>,
    /// G.
    g: f64,
}

impl Jacobi {
    /// The splitting for positive masses `masses` (at least one) and constant `g`.
    pub(crate) fn new(masses: &[f64], g: f64) -> Self {
        let mut eta = Vec::with_capacity(masses.len());
        let mut sum = 0.0;
        for &m in masses {
            sum += m;
            eta.push(sum);
        }
        let jacobi_masses = (0..masses.len())
            .map(|i| {
                if i == 0 {
                    sum
                } else {
                    masses[i] * eta[i - 1] / eta[i]
                }
            })
            .collect();
        let mu = eta.iter().map(|e| g * e).collect();
        Jacobi {
            masses: masses.to_vec(),
            eta,
            jacobi_masses,
            mu,
            g,
        }
    }

    /// Number of bodies N.
    pub(crate) fn bodies(&self) -> usize {
        self.masses.len()
    }

    /// The Jacobi mass m′ᵢ (the total mass for i = 0).
    pub(crate) fn jacobi_mass(&self, i: usize) -> f64 {
        self.jacobi_masses[i]
    }

    /// The Kepler problem's gravitational parameter μᵢ = G ηᵢ of Jacobi body i ≥ 1.
    pub(crate) fn mu(&self, i: usize) -> f64 {
        self.mu[i]
    }

    /// Jacobi positions from Cartesian ones (r′₀ the centre of mass).
    pub(crate) fn positions_to_jacobi(&self, r: &[[f64; 3]], out: &mut [[f64; 3]]) {
        // Running Σ_{j<i} mⱼ rⱼ; r′ᵢ = rᵢ − (that sum)/ηᵢ₋₁.
        let mut moment = scale(self.masses[0], r[0]);
        for i in 1..self.bodies() {
            let centre = scale(1.0 / self.eta[i - 1], moment);
            out[i] = sub(r[i], centre);
            moment = add(moment, scale(self.masses[i], r[i]));
        }
        out[0] = scale(1.0 / self.eta[self.bodies() - 1], moment);
    }

    /// Cartesian positions from Jacobi ones: from the outermost body in, Rᵢ₋₁ = Rᵢ − mᵢ r′ᵢ/ηᵢ
    /// and rᵢ = r′ᵢ + Rᵢ₋₁, with R_{N−1} = r′₀ and r₀ = R₀.
    pub(crate) fn positions_from_jacobi(&self, rj: &[[f64; 3]], out: &mut [[f64; 3]]) {
        let mut centre = rj[0];
        for i in (1..self.bodies()).rev() {
            centre = sub(centre, scale(self.masses[i] / self.eta[i], rj[i]));
            out[i] = add(rj[i], centre);
        }
        out[0] = centre;
    }

    /// Jacobi momenta from Cartesian ones, p′ᵢ = (ηᵢ₋₁ pᵢ − mᵢ Σ_{j<i} pⱼ)/ηᵢ and p′₀ = Σ pᵢ:
    /// the transpose (∂r/∂r′)ᵀ, which also maps a Cartesian gradient to the Jacobi one.
    pub(crate) fn covector_to_jacobi(&self, p: &[[f64; 3]], out: &mut [[f64; 3]]) {
        let mut below = p[0];
        for i in 1..self.bodies() {
            let a = scale(self.eta[i - 1], p[i]);
            out[i] = scale(1.0 / self.eta[i], sub(a, scale(self.masses[i], below)));
            below = add(below, p[i]);
        }
        out[0] = below;
    }

    /// Cartesian momenta from Jacobi ones, the inverse of
    /// [`covector_to_jacobi`](Self::covector_to_jacobi): from the outermost body in, with
    /// S = Σ_{j≤i} pⱼ, Σ_{j<i} pⱼ = (ηᵢ₋₁/ηᵢ) S − p′ᵢ and pᵢ = S − Σ_{j<i} pⱼ.
    pub(crate) fn covector_from_jacobi(&self, pj: &[[f64; 3]], out: &mut [[f64; 3]]) {
        let mut upto = pj[0];
        for i in (1..self.bodies()).rev() {
            let below = sub(scale(self.eta[i - 1] / self.eta[i], upto), pj[i]);
            out[i] = sub(upto, below);
            upto = below;
        }
        out[0] = upto;
    }

    /// ∂H_I/∂r′ at Jacobi positions `rj` into `out` (entry 0 unused, set to 0), with
    /// `cartesian` scratch for the Cartesian positions and their gradient (N entries each).
    ///
    /// The Cartesian gradient of −Σ G mᵢ mⱼ/|rᵢ − rⱼ| is mapped by the covector transform and
    /// the Kepler terms' gradient −G m′ᵢ ηᵢ r′ᵢ/|r′ᵢ|³ is added: for each planet the star's pull
    /// and its Kepler part nearly cancel, leaving the perturbation.
    pub(crate) fn interaction_gradient(
        &self,
        rj: &[[f64; 3]],
        cartesian: &mut [[f64; 3]],
        cartesian_gradient: &mut [[f64; 3]],
        out: &mut [[f64; 3]],
    ) {
        let n = self.bodies();
        self.positions_from_jacobi(rj, cartesian);
        cartesian_gradient.iter_mut().for_each(|x| *x = [0.0; 3]);
        for i in 0..n {
            let ri = cartesian[i];
            let mut gi = cartesian_gradient[i];
            let gmi = self.g * self.masses[i];
            for j in i + 1..n {
                let d = sub(ri, cartesian[j]);
                let r2 = dot(d, d);
                let f = gmi * self.masses[j] / (r2 * r2.sqrt());
                gi = add(gi, scale(f, d));
                cartesian_gradient[j] = sub(cartesian_gradient[j], scale(f, d));
            }
            cartesian_gradient[i] = gi;
        }
        self.covector_to_jacobi(cartesian_gradient, out);
        out[0] = [0.0; 3];
        for i in 1..n {
            let r2 = dot(rj[i], rj[i]);
            let k = self.jacobi_masses[i] * self.mu[i] / (r2 * r2.sqrt());
            out[i] = sub(out[i], scale(k, rj[i]));
        }
    }

    /// H_I at Jacobi positions (for the tests).
    #[cfg(test)]
    pub(crate) fn interaction(&self, rj: &[[f64; 3]], cartesian: &mut [[f64; 3]]) -> f64 {
        let n = self.bodies();
        self.positions_from_jacobi(rj, cartesian);
        let mut h = 0.0;
        for i in 1..n {
            h += self.jacobi_masses[i] * self.mu[i] / dot(rj[i], rj[i]).sqrt();
        }
        for i in 0..n {
            for j in i + 1..n {
                let d = sub(cartesian[i], cartesian[j]);
                h -= self.g * self.masses[i] * self.masses[j] / dot(d, d).sqrt();
            }
        }
        h
    }
}

#[inline(always)]
pub(crate) fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

#[inline(always)]
pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
pub(crate) fn scale(s: f64, a: [f64; 3]) -> [f64; 3] {
    [s * a[0], s * a[1], s * a[2]]
}

#[inline(always)]
pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
