//! A synthetic planetesimal ring: a central star and many small equal-mass bodies on
//! near-circular, slightly eccentric and inclined orbits — an N-body configuration of any size
//! for scaling studies (`gvi solver-scaling`, `scenes/planetesimal-ring.toml`).
//!
//! Units with G = 1 and a star of mass 1: an orbit of semi-major axis a has period
//! 2π a^{3/2}. The orbital elements are drawn from a SplitMix64 stream of the seed (a fixed,
//! documented generator rather than `rand`'s `StdRng`, whose stream may change between
//! versions), so a (configuration, seed) pair always gives the same bodies, bit for bit:
//! a uniform in [inner, outer], e uniform in [0, max_eccentricity], i uniform in
//! [0, max_inclination], Ω, ω and the true anomaly f uniform in [0, 2π). Positions and
//! velocities are the two-body (star + planetesimal) Keplerian ones, heliocentric, and are then
//! moved to the barycentric frame exactly as a scene with `barycentric = true` is.

use crate::error::LabError;
use crate::error::Result;
use crate::nbody_scene::Body;
use galerkin_vi::method::InitialState;
use galerkin_vi::systems::NBody;
use std::f64::consts::TAU;

/// Parameters of [`planetesimal_ring`].
#[derive(Debug, Clone, PartialEq)]
pub struct RingConfig {
    /// Number of bodies N (the star and N − 1 planetesimals); at least 2.
    pub bodies: usize,
    /// Mass of each planetesimal (the star has mass 1, G = 1).
    pub planetesimal_mass: f64,
    /// Smallest semi-major axis.
    pub inner: f64,
    /// Largest semi-major axis.
    pub outer: f64,
    /// Largest eccentricity.
    pub max_eccentricity: f64,
    /// Largest inclination (radians).
    pub max_inclination: f64,
    /// Seed of the SplitMix64 stream.
    pub seed: u64,
}

impl Default for RingConfig {
    /// 16 bodies, planetesimal mass 1e-7, a ∈ [1, 2], e ≤ 0.05, i ≤ 0.05 rad, seed 2026.
    fn default() -> Self {
        RingConfig {
            bodies: 16,
            planetesimal_mass: 1e-7,
            inner: 1.0,
            outer: 2.0,
            max_eccentricity: 0.05,
            max_inclination: 0.05,
            seed: 2026,
        }
    }
}

impl RingConfig {
    /// The default ring with `bodies` bodies.
    pub fn with_bodies(bodies: usize) -> Self {
        RingConfig {
            bodies,
            ..RingConfig::default()
        }
    }

    /// One eighth of the orbital period at the inner edge, 2π·inner^{3/2}/8: the step the
    /// scaling study uses.
    pub fn step(&self) -> f64 {
        TAU * self.inner.powf(1.5) / 8.0
    }

    fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: String| LabError::InvalidArgument {
            name: name.into(),
            reason,
        };
        if self.bodies < 2 {
            return Err(bad(
                "bodies",
                format!(
                    "a ring needs the star and at least one planetesimal, got N = {}",
                    self.bodies
                ),
            ));
        }
        if self.bodies > 100_000 {
            return Err(bad(
                "bodies",
                format!("N = {} is absurdly large", self.bodies),
            ));
        }
        let m = self.planetesimal_mass;
        if !(m.is_finite() && m > 0.0 && m < 1.0) {
            return Err(bad(
                "planetesimal_mass",
                format!("must be in (0, 1), got {m}"),
            ));
        }
        let (a, b) = (self.inner, self.outer);
        if !(a.is_finite() && b.is_finite() && a > 0.0 && b >= a) {
            return Err(bad(
                "inner/outer",
                format!("need 0 < inner ≤ outer, finite; got {a}, {b}"),
            ));
        }
        let e = self.max_eccentricity;
        if !(e.is_finite() && (0.0..0.9).contains(&e)) {
            return Err(bad(
                "max_eccentricity",
                format!("must be in [0, 0.9), got {e}"),
            ));
        }
        let i = self.max_inclination;
        if !(i.is_finite() && (0.0..=std::f64::consts::FRAC_PI_2).contains(&i)) {
            return Err(bad(
                "max_inclination",
                format!("must be in [0, π/2], got {i}"),
            ));
        }
        Ok(())
    }

    /// The bodies (heliocentric positions and velocities), named `Star`, `P01`, `P02`, ….
    pub fn bodies(&self) -> Result<Vec<Body>> {
        self.validate()?;
        let mut rng = SplitMix64(self.seed);
        let mut out = Vec::with_capacity(self.bodies);
        out.push(Body {
            name: "Star".into(),
            mass: Some(1.0),
            gm: None,
            q: vec![0.0; 3],
            v: vec![0.0; 3],
        });
        let width = (self.bodies - 1).to_string().len().max(2);
        let mu = 1.0 + self.planetesimal_mass;
        for k in 1..self.bodies {
            let a = self.inner + (self.outer - self.inner) * rng.uniform();
            let e = self.max_eccentricity * rng.uniform();
            let inc = self.max_inclination * rng.uniform();
            let (node, peri, f) = (
                TAU * rng.uniform(),
                TAU * rng.uniform(),
                TAU * rng.uniform(),
            );
            let (q, v) = kepler_to_cartesian(mu, a, e, inc, node, peri, f);
            out.push(Body {
                name: format!("P{k:0width$}"),
                mass: Some(self.planetesimal_mass),
                gm: None,
                q: q.to_vec(),
                v: v.to_vec(),
            });
        }
        Ok(out)
    }

    /// The scene file text (`scenes/planetesimal-ring.toml` is this for the default ring).
    pub fn scene_toml(&self) -> Result<String> {
        let bodies = self.bodies()?;
        let mut s = format!(
            "# A synthetic planetesimal ring (not observational data): a star of mass 1 and \
             {} planetesimals\n# of mass {:e} on near-circular orbits, a ∈ [{}, {}], e ≤ {}, \
             i ≤ {} rad, G = 1.\n# Generated by galerkin_vi::systems::RingConfig (seed {}; \
             SplitMix64 stream, see\n# src/systems/ring.rs); regenerate with\n#   \
             GVI_WRITE_RING_SCENE=1 cargo test -p galerkin-vi-lab --test integration scaling::ring_scene_file\n# The step \
             h = 2π/8 is 1/8 of the innermost orbital period. `gvi solver-scaling` builds rings \
             of 2…64 bodies\n# from the same generator.\n",
            self.bodies - 1,
            self.planetesimal_mass,
            self.inner,
            self.outer,
            self.max_eccentricity,
            self.max_inclination,
            self.seed
        );
        s.push_str("name = \"planetesimal-ring\"\n");
        s.push_str(&format!(
            "description = \"Synthetic ring: star + {} planetesimals (mass {:e}), a in [{}, {}], \
             h = 1/8 inner period\"\n",
            self.bodies - 1,
            self.planetesimal_mass,
            self.inner,
            self.outer
        ));
        s.push_str(
            "source = \"Synthetic (galerkin_vi::systems::RingConfig::default()); no observational \
             data\"\n\n[system]\ntype = \"nbody\"\ndim = 3\ng = 1.0\nbarycentric = true\n",
        );
        let list = |x: &[f64]| {
            x.iter()
                .map(|v| format!("{v:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        for b in &bodies {
            s.push_str(&format!(
                "\n[[system.bodies]]\nname = \"{}\"\nmass = {:?}\nq = [{}]\nv = [{}]\n",
                b.name,
                b.mass.unwrap_or(0.0),
                list(&b.q),
                list(&b.v)
            ));
        }
        s.push_str(&format!(
            "\n[method]\nbasis = \"chebyshev\"\nquadrature = \"gauss-legendre\"\nn = 16\nh = {:?}\n\
             steps = 80\n",
            self.step()
        ));
        Ok(s)
    }
}

/// The ring of `config` as an N-body system (3-D, G = 1) with its barycentric initial state
/// (p = m v). Invalid parameters (N < 2, non-finite or non-positive sizes) are
/// [`LabError::InvalidArgument`].
///
/// ```
/// use galerkin_vi_lab::ring::{RingConfig, planetesimal_ring};
/// let (system, init) = planetesimal_ring(&RingConfig::with_bodies(8))?;
/// assert_eq!((system.bodies(), init.q.len()), (8, 24));
/// # Ok::<(), galerkin_vi_lab::error::LabError>(())
/// ```
pub fn planetesimal_ring(config: &RingConfig) -> Result<(NBody, InitialState)> {
    let bodies = config.bodies()?;
    crate::nbody_scene::build(3, Some(1.0), None, true, &bodies)
}

/// Position and velocity of a two-body orbit with parameter μ from its elements (semi-major
/// axis, eccentricity, inclination, longitude of the node, argument of periapsis, true anomaly).
fn kepler_to_cartesian(
    mu: f64,
    a: f64,
    e: f64,
    inc: f64,
    node: f64,
    peri: f64,
    f: f64,
) -> ([f64; 3], [f64; 3]) {
    let p = a * (1.0 - e * e);
    let r = p / (1.0 + e * f.cos());
    let (x, y) = (r * f.cos(), r * f.sin());
    let w = (mu / p).sqrt();
    let (vx, vy) = (-w * f.sin(), w * (e + f.cos()));
    // Rotation Rz(Ω) Rx(i) Rz(ω) of the perifocal frame.
    let (co, so) = (node.cos(), node.sin());
    let (ci, si) = (inc.cos(), inc.sin());
    let (cw, sw) = (peri.cos(), peri.sin());
    let rot = [
        [co * cw - so * ci * sw, -co * sw - so * ci * cw],
        [so * cw + co * ci * sw, -so * sw + co * ci * cw],
        [si * sw, si * cw],
    ];
    let apply = |u: f64, v: f64| [0, 1, 2].map(|row| rot[row][0] * u + rot[row][1] * v);
    (apply(x, y), apply(vx, vy))
}

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny, fixed, well-mixed 64-bit stream. Kept on
/// purpose instead of `rand` (the tests use rand): a scene must give the same bodies under
/// every version of rand, whose generators and streams may change.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1) with 53 random bits.
    fn uniform(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}
