//! The gravitational N-body problem in 2 or 3 dimensions (paper §5.2.2, "The Solar System").

use super::{System, positive};
use crate::error::{GviError, Result, ensure_len};
use crate::lagrangian::{ByCoordinate, Mechanical};
use crate::symmetries::{NamedMomentumMap, Rotation, Translation};
use nalgebra::DMatrix;
use num_dual::DualNum;

mod pairwise;

/// N point masses under Newtonian gravity,
/// L = Σᵢ ½ mᵢ |q̇ᵢ|² + Σ_{i<j} G mᵢ mⱼ / |qᵢ − qⱼ|.
///
/// **Flattening** is body-major: with `dim` = 3 the configuration is
/// q = (x₀, y₀, z₀, x₁, y₁, z₁, …), body 0 first, in the order the bodies were given
/// (the scene's order). Momenta are p = m v in the same layout.
///
/// **Masses.** [`NBody::new`] takes masses and the constant G. [`NBody::from_gm`] takes the
/// gravitational parameters GMᵢ (what ephemerides publish, e.g. AU³/day²) and uses them *as
/// the masses* with G = 1: the Lagrangian is then G times the physical one, which has the same
/// Euler–Lagrange equations (the same motion) but momenta scaled by G (pᵢ = GMᵢ vᵢ), and energy
/// and momenta in units of G × the physical ones.
///
/// The gradient and Hessian of the potential are hand-written (pairwise, O(N²)); automatic
/// differentiation of [`potential`](Mechanical::potential) is used only to test them.
///
/// **Invariants** (`invariant_names`): `energy` (H = Σ|pᵢ|²/2mᵢ + V), the total linear
/// momentum `px`, `py` (and `pz` in 3-D), and the total angular momentum about the origin:
/// `angular_momentum` (= Σ xᵢ p_{y,i} − yᵢ p_{x,i}) in 2-D, its components `lx`, `ly`, `lz`
/// in 3-D. The symmetries (translations along each axis, rotations in each coordinate plane)
/// carry the same names.
///
/// ```
/// use galerkin_vi::systems::{NBody, System};
/// // Two unit masses a unit distance apart, at rest: V = −1.
/// let nb = NBody::new(vec![1.0, 1.0], 1.0, 2)?;
/// let mut inv = [0.0; 4];
/// nb.invariants(&[0.0, 0.0, 1.0, 0.0], &[0.0; 4], &mut inv);
/// assert_eq!(nb.invariant_names(), ["energy", "px", "py", "angular_momentum"]);
/// assert!((inv[0] + 1.0).abs() < 1e-15);
/// # Ok::<(), galerkin_vi::GviError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct NBody {
    masses: Vec<f64>,
    g: f64,
    dim: usize,
    names: Option<Vec<String>>,
}

impl NBody {
    /// Bodies of the given masses (each finite and positive), gravitational constant `g` > 0,
    /// in `dim` ∈ {2, 3} dimensions. At least one body.
    pub fn new(masses: Vec<f64>, g: f64, dim: usize) -> Result<Self> {
        if dim != 2 && dim != 3 {
            return Err(GviError::InvalidInput {
                name: "dim".into(),
                reason: format!("the N-body problem is modelled in 2 or 3 dimensions, got {dim}"),
            });
        }
        if masses.is_empty() {
            return Err(GviError::InvalidInput {
                name: "masses".into(),
                reason: "need at least one body".into(),
            });
        }
        for (i, &m) in masses.iter().enumerate() {
            positive(&format!("mass of body {i}"), m)?;
        }
        Ok(NBody {
            masses,
            g: positive("G", g)?,
            dim,
            names: None,
        })
    }

    /// Bodies given by their gravitational parameters GMᵢ: the masses are the GMᵢ and G = 1
    /// (same dynamics; momenta pᵢ = GMᵢ vᵢ — see the type's documentation).
    pub fn from_gm(gms: Vec<f64>, dim: usize) -> Result<Self> {
        NBody::new(gms, 1.0, dim)
    }

    /// Attach body names (one per body), used for charts and reports.
    pub fn with_names(mut self, names: Vec<String>) -> Result<Self> {
        ensure_len("body names", self.masses.len(), names.len())?;
        self.names = Some(names);
        Ok(self)
    }

    /// Number of bodies N.
    pub fn bodies(&self) -> usize {
        self.masses.len()
    }

    /// Dimension of each body (2 or 3).
    pub fn body_dim(&self) -> usize {
        self.dim
    }

    /// The masses (the kinetic masses: GM values for [`NBody::from_gm`]).
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// The gravitational constant G (1 for [`NBody::from_gm`]).
    pub fn g(&self) -> f64 {
        self.g
    }

    /// The body names, if set.
    pub fn names(&self) -> Option<&[String]> {
        self.names.as_deref()
    }

    /// Index of the body called `name`, if names are set.
    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.names.as_ref()?.iter().position(|n| n == name)
    }

    /// The closest pair of bodies of a flattened configuration: (i, j, |xᵢ − xⱼ|) with i < j;
    /// `None` for fewer than two bodies or a configuration of the wrong length.
    ///
    /// ```
    /// use galerkin_vi::systems::NBody;
    /// let nb = NBody::new(vec![1.0, 1.0, 1.0], 1.0, 2)?;
    /// let q = [0.0, 0.0, 3.0, 0.0, 3.0, 0.5];
    /// assert_eq!(nb.closest_pair(&q), Some((1, 2, 0.5)));
    /// # Ok::<(), galerkin_vi::GviError>(())
    /// ```
    pub fn closest_pair(&self, q: &[f64]) -> Option<(usize, usize, f64)> {
        let (d, n) = (self.dim, self.masses.len());
        if n < 2 || q.len() != n * d {
            return None;
        }
        let mut best = (0, 1, f64::INFINITY);
        for i in 0..n {
            for j in i + 1..n {
                let r2: f64 = (0..d).map(|k| (q[i * d + k] - q[j * d + k]).powi(2)).sum();
                if r2 < best.2 {
                    best = (i, j, r2);
                }
            }
        }
        Some((best.0, best.1, best.2.sqrt()))
    }

    /// Total mass Σ mᵢ.
    pub fn total_mass(&self) -> f64 {
        self.masses.iter().sum()
    }

    /// Centre of mass Σ mᵢ xᵢ / Σ mᵢ of a flattened configuration (or of velocities).
    pub fn centre_of_mass(&self, x: &[f64]) -> Vec<f64> {
        let d = self.dim;
        let mut c = vec![0.0; d];
        for (b, &m) in self.masses.iter().enumerate() {
            for k in 0..d {
                c[k] += m * x.get(b * d + k).copied().unwrap_or(0.0);
            }
        }
        let total = self.total_mass();
        c.iter_mut().for_each(|x| *x /= total);
        c
    }

    /// Move positions and velocities to the barycentric frame: subtract the centre-of-mass
    /// position from every qᵢ and the centre-of-mass velocity from every vᵢ.
    ///
    /// ```
    /// use galerkin_vi::systems::NBody;
    /// let nb = NBody::new(vec![3.0, 1.0], 1.0, 2)?;
    /// let (mut q, mut v) = (vec![0.0, 0.0, 4.0, 0.0], vec![0.0, 0.0, 0.0, 4.0]);
    /// nb.to_barycentric(&mut q, &mut v)?;
    /// assert_eq!(q, [-1.0, 0.0, 3.0, 0.0]);
    /// assert_eq!(v, [0.0, -1.0, 0.0, 3.0]);
    /// # Ok::<(), galerkin_vi::GviError>(())
    /// ```
    pub fn to_barycentric(&self, q: &mut [f64], v: &mut [f64]) -> Result<()> {
        let n = self.degrees_of_freedom();
        ensure_len("positions", n, q.len())?;
        ensure_len("velocities", n, v.len())?;
        for x in [q, v] {
            let c = self.centre_of_mass(x);
            for (i, xi) in x.iter_mut().enumerate() {
                *xi -= c[i % self.dim];
            }
        }
        Ok(())
    }

    /// Momenta p = m v from velocities.
    pub fn momenta(&self, v: &[f64]) -> Vec<f64> {
        v.iter()
            .enumerate()
            .map(|(i, x)| self.masses[i / self.dim] * x)
            .collect()
    }

    /// Velocities v = p / m from momenta.
    pub fn velocities(&self, p: &[f64]) -> Vec<f64> {
        p.iter()
            .enumerate()
            .map(|(i, x)| x / self.masses[i / self.dim])
            .collect()
    }

    /// Separation qᵢ − qⱼ into `d` (length ≤ 3) and returns |qᵢ − qⱼ|².
    #[inline]
    fn separation(&self, q: &[f64], i: usize, j: usize, d: &mut [f64; 3]) -> f64 {
        let k = self.dim;
        let mut r2 = 0.0;
        for c in 0..k {
            d[c] = q[i * k + c] - q[j * k + c];
            r2 += d[c] * d[c];
        }
        r2
    }

    /// Every pair i < j with d = qᵢ − qⱼ, a = κ/r³ and b = 3κ/r⁵ (κ = G mᵢ mⱼ): the pair's
    /// force is a·d and its Hessian block B = a I − b d dᵀ. The gradient, the Hessian, its
    /// diagonal blocks and its products are sums over these, in this order.
    #[inline]
    fn for_each_pair(&self, q: &[f64], mut f: impl FnMut(usize, usize, &[f64; 3], f64, f64)) {
        let nb = self.masses.len();
        let mut d = [0.0; 3];
        for i in 0..nb {
            for j in i + 1..nb {
                let r2 = self.separation(q, i, j, &mut d);
                let a = self.g * self.masses[i] * self.masses[j] / (r2 * r2.sqrt());
                f(i, j, &d, a, 3.0 * a / r2);
            }
        }
    }
}

/// Entry (r, s) of a pair's Hessian block B = a I − b d dᵀ (a = κ/r³, b = 3κ/r⁵).
#[inline]
fn pair_block_entry(d: &[f64; 3], a: f64, b: f64, r: usize, s: usize) -> f64 {
    let blk = -b * d[r] * d[s];
    if r == s { blk + a } else { blk }
}

impl NBody {
    /// ∇²V(q)·x pairwise, never forming the Hessian: with B_ij = κ (I/r³ − 3 d dᵀ/r⁵) the
    /// pair block of [`Mechanical::potential_hessian`], (∇²V x)_i = Σ_j B_ij (x_i − x_j).
    fn potential_hessian_product(&self, q: &[f64], x: &[f64], out: &mut [f64]) {
        let k = self.dim;
        out.iter_mut().for_each(|y| *y = 0.0);
        self.for_each_pair(q, |i, j, d, a, b| {
            let mut dx = [0.0; 3];
            let mut dot = 0.0;
            for c in 0..k {
                dx[c] = x[i * k + c] - x[j * k + c];
                dot += d[c] * dx[c];
            }
            for c in 0..k {
                let y = a * dx[c] - b * dot * d[c];
                out[i * k + c] += y;
                out[j * k + c] -= y;
            }
        });
    }

    /// The diagonal k×k blocks of ∇²V(q), body after body (the same sums, in the same order,
    /// as the diagonal of [`Mechanical::potential_hessian`]).
    fn potential_hessian_diagonal_blocks(&self, q: &[f64], out: &mut [f64]) {
        if self.dim == 2 {
            pairwise::hessian_diagonal_blocks::<2>(self.g, &self.masses, q, out);
        } else {
            pairwise::hessian_diagonal_blocks::<3>(self.g, &self.masses, q, out);
        }
    }
}

impl Mechanical for NBody {
    fn degrees_of_freedom(&self) -> usize {
        self.masses.len() * self.dim
    }

    fn mass(&self) -> DMatrix<f64> {
        let n = self.degrees_of_freedom();
        DMatrix::from_fn(n, n, |r, s| {
            if r == s {
                self.masses[r / self.dim]
            } else {
                0.0
            }
        })
    }

    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T {
        let (k, nb) = (self.dim, self.masses.len());
        let mut v = T::from(0.0);
        for i in 0..nb {
            for j in i + 1..nb {
                let mut r2 = T::from(0.0);
                for c in 0..k {
                    let d = q[i * k + c] - q[j * k + c];
                    r2 += d * d;
                }
                v -= r2.sqrt().recip() * (self.g * self.masses[i] * self.masses[j]);
            }
        }
        v
    }

    fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
        // dim is 2 or 3 (the constructors check it): the pairwise sums with it a constant.
        if self.dim == 2 {
            pairwise::gradient::<2>(self.g, &self.masses, q, out);
        } else {
            pairwise::gradient::<3>(self.g, &self.masses, q, out);
        }
    }

    fn coordinate_blocks(&self) -> Option<usize> {
        Some(self.dim)
    }

    fn potential_gradient_at_points(&self, q: &[f64], out: &mut [f64]) {
        let d = self.degrees_of_freedom();
        // The nodes side by side in vector lanes (the same bits as node by node), unless
        // there are enough bodies for one rayon task per node.
        if self.masses.len() < PARALLEL_BODIES || !cfg!(feature = "parallel") {
            if self.dim == 2 {
                pairwise::gradient_at_points::<2>(self.g, &self.masses, q, d, out);
            } else {
                pairwise::gradient_at_points::<3>(self.g, &self.masses, q, d, out);
            }
            return;
        }
        for_each_node(self.masses.len(), q, d, None, out, d, |qj, _, oj| {
            self.potential_gradient(qj, oj)
        });
    }

    fn potential_gradient_at_points_on_blocks(&self, q: &[f64], active: &[bool], out: &mut [f64]) {
        let d = self.degrees_of_freedom();
        // The pairs with an active body, in vector lanes; the parallel evaluation of many
        // bodies computes them all.
        if self.masses.len() < PARALLEL_BODIES || !cfg!(feature = "parallel") {
            if self.dim == 2 {
                pairwise::gradient_at_points_on::<2>(self.g, &self.masses, q, d, active, out);
            } else {
                pairwise::gradient_at_points_on::<3>(self.g, &self.masses, q, d, active, out);
            }
            return;
        }
        self.potential_gradient_at_points(q, out);
    }

    fn potential_gradient_at_points_by_coordinate_on_blocks(
        &self,
        q: &[f64],
        layout: ByCoordinate,
        active: &[bool],
        out: &mut [f64],
    ) {
        let d = self.degrees_of_freedom();
        // The rows in vector lanes as they lie; many bodies go through the points (the
        // parallel evaluation).
        if self.masses.len() < PARALLEL_BODIES || !cfg!(feature = "parallel") {
            if self.dim == 2 {
                pairwise::gradient_by_coordinate_on::<2>(
                    self.g,
                    &self.masses,
                    q,
                    d,
                    layout,
                    active,
                    out,
                );
            } else {
                pairwise::gradient_by_coordinate_on::<3>(
                    self.g,
                    &self.masses,
                    q,
                    d,
                    layout,
                    active,
                    out,
                );
            }
            return;
        }
        layout.through_points(d, self.dim, q, active, out, |qp, op| {
            self.potential_gradient_at_points(qp, op)
        });
    }

    fn potential_hessian_at_points(&self, q: &[f64], out: &mut [f64]) {
        let d = self.degrees_of_freedom();
        for_each_node(self.masses.len(), q, d, None, out, d * d, |qj, _, oj| {
            self.potential_hessian(qj, oj)
        });
    }

    fn potential_hessian_products_at_points(&self, q: &[f64], x: &[f64], out: &mut [f64]) -> bool {
        let d = self.degrees_of_freedom();
        for_each_node(self.masses.len(), q, d, Some(x), out, d, |qj, xj, oj| {
            self.potential_hessian_product(qj, xj, oj)
        });
        true
    }

    fn potential_hessian_diagonal_blocks_at_points(&self, q: &[f64], out: &mut [f64]) -> bool {
        let d = self.degrees_of_freedom();
        let per_point = self.masses.len() * self.dim * self.dim;
        // The nodes side by side in vector lanes (the same bits as node by node), unless
        // there are enough bodies for one rayon task per node.
        if self.masses.len() < PARALLEL_BODIES || !cfg!(feature = "parallel") {
            if self.dim == 2 {
                pairwise::hessian_blocks_at_points::<2>(self.g, &self.masses, q, d, out);
            } else {
                pairwise::hessian_blocks_at_points::<3>(self.g, &self.masses, q, d, out);
            }
            return true;
        }
        for_each_node(
            self.masses.len(),
            q,
            d,
            None,
            out,
            per_point,
            |qj, _, oj| self.potential_hessian_diagonal_blocks(qj, oj),
        );
        true
    }

    fn potential_hessian(&self, q: &[f64], out: &mut [f64]) {
        // Pair (i, j) with d = qᵢ − qⱼ, r = |d|, κ = G mᵢ mⱼ:
        // B = κ (I/r³ − 3 d dᵀ/r⁵) adds to blocks (i,i), (j,j) and subtracts from (i,j), (j,i).
        let k = self.dim;
        let n = self.masses.len() * k;
        out.iter_mut().for_each(|x| *x = 0.0);
        self.for_each_pair(q, |i, j, d, a, b| {
            for r in 0..k {
                for s in 0..k {
                    let blk = pair_block_entry(d, a, b, r, s);
                    out[(i * k + r) * n + i * k + s] += blk;
                    out[(j * k + r) * n + j * k + s] += blk;
                    out[(i * k + r) * n + j * k + s] -= blk;
                    out[(j * k + r) * n + i * k + s] -= blk;
                }
            }
        });
    }
}

/// Number of bodies from which forces and Hessians at the quadrature nodes of a step are
/// evaluated in parallel (rayon, one node per task). Measured on a 2-core machine with the
/// planetesimal ring (n = 16, Newton–Krylov, 64 steps): forces and Hessians are 30 % of a step
/// at N = 128, and the parallel evaluation saves 5 % there (50.3 against 52.7 ms per step) and
/// nothing measurable at N = 16…64 (0.8, 3.0, 12.2 ms per step either way).
pub const PARALLEL_BODIES: usize = 128;

/// Apply `f(q_j, x_j, out_j)` at every quadrature node (`q` in chunks of `d`, the optional
/// direction `x` in chunks of `d`, `out` in chunks of `out_len`): in parallel (rayon, one node
/// per task) from [`PARALLEL_BODIES`] bodies when the `parallel` feature is on, serially
/// otherwise. The same arithmetic per node either way, so the results are identical.
fn for_each_node<F>(
    bodies: usize,
    q: &[f64],
    d: usize,
    x: Option<&[f64]>,
    out: &mut [f64],
    out_len: usize,
    f: F,
) where
    F: Fn(&[f64], &[f64], &mut [f64]) + Sync,
{
    let nodes = q.len() / d.max(1);
    let x_len = if x.is_some() { d } else { 0 };
    let x = x.unwrap_or(&[]);
    let x_of = |j: usize| &x[j * x_len..(j + 1) * x_len];
    let parallel = bodies >= PARALLEL_BODIES;
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        out.par_chunks_exact_mut(out_len)
            .take(nodes)
            .enumerate()
            .for_each(|(j, oj)| f(&q[j * d..(j + 1) * d], x_of(j), oj));
        return;
    }
    let _ = parallel; // serial without the `parallel` feature
    for (j, oj) in out.chunks_exact_mut(out_len).take(nodes).enumerate() {
        f(&q[j * d..(j + 1) * d], x_of(j), oj);
    }
}

const NAMES_2D: [&str; 4] = ["energy", "px", "py", "angular_momentum"];
const NAMES_3D: [&str; 7] = ["energy", "px", "py", "pz", "lx", "ly", "lz"];

impl System for NBody {
    fn shortest_time_scale(&self, q: &[f64], _p: &[f64]) -> Option<f64> {
        let (nb, k) = (self.bodies(), self.body_dim());
        let ms = self.masses();
        let mut shortest = f64::INFINITY;
        for i in 0..nb {
            for j in i + 1..nb {
                let r2: f64 = (0..k).map(|c| (q[i * k + c] - q[j * k + c]).powi(2)).sum();
                let period =
                    std::f64::consts::TAU * (r2 * r2.sqrt() / (self.g() * (ms[i] + ms[j]))).sqrt();
                shortest = shortest.min(period);
            }
        }
        (shortest.is_finite() && shortest > 0.0).then_some(shortest)
    }

    fn name(&self) -> &'static str {
        "nbody"
    }

    fn invariant_names(&self) -> &'static [&'static str] {
        if self.dim == 2 { &NAMES_2D } else { &NAMES_3D }
    }

    fn invariants(&self, q: &[f64], p: &[f64], out: &mut [f64]) {
        let k = self.dim;
        let kinetic: f64 = p
            .iter()
            .enumerate()
            .map(|(i, x)| 0.5 * x * x / self.masses[i / k])
            .sum();
        out[0] = kinetic + self.potential(q);
        let mut lin = [0.0; 3];
        let mut ang = [0.0; 3];
        for b in 0..self.masses.len() {
            let (x, m) = (&q[b * k..(b + 1) * k], &p[b * k..(b + 1) * k]);
            for c in 0..k {
                lin[c] += m[c];
            }
            if k == 2 {
                ang[2] += x[0] * m[1] - x[1] * m[0];
            } else {
                ang[0] += x[1] * m[2] - x[2] * m[1];
                ang[1] += x[2] * m[0] - x[0] * m[2];
                ang[2] += x[0] * m[1] - x[1] * m[0];
            }
        }
        out[1..=k].copy_from_slice(&lin[..k]);
        if k == 2 {
            out[3] = ang[2];
        } else {
            out[4..7].copy_from_slice(&ang);
        }
    }

    fn symmetries(&self) -> Vec<NamedMomentumMap> {
        let (k, nb) = (self.dim, self.masses.len());
        let mut maps = Vec::new();
        for (axis, name) in ["px", "py", "pz"].iter().enumerate().take(k) {
            if let Ok(t) = Translation::axis(k, nb, axis) {
                maps.push(NamedMomentumMap {
                    name: (*name).into(),
                    map: Box::new(t),
                });
            }
        }
        // Rotation in the (i, j) plane: J = Σ qᵢ p_j − q_j pᵢ.
        let planes: &[(usize, usize, &str)] = if k == 2 {
            &[(0, 1, "angular_momentum")]
        } else {
            &[(1, 2, "lx"), (2, 0, "ly"), (0, 1, "lz")]
        };
        for &(i, j, name) in planes {
            if let Ok(rot) = Rotation::planar(k, nb, i, j) {
                maps.push(NamedMomentumMap {
                    name: name.into(),
                    map: Box::new(rot),
                });
            }
        }
        maps
    }

    fn body_names(&self) -> Option<Vec<String>> {
        Some(
            self.names
                .clone()
                .unwrap_or_else(|| (0..self.bodies()).map(|b| format!("body {b}")).collect()),
        )
    }
}

#[cfg(test)]
mod tests;
