//! Rigid bodies on SO(3): the left-trivialised Lagrangian ℓ(R, Ω) = ½ Ω·𝕀Ω − V(R) with a
//! diagonal (principal-axes) inertia 𝕀 and a potential V(R).
//!
//! The body momentum is μ = 𝕀Ω, the spatial angular momentum R μ, the energy ½ μ·𝕀⁻¹μ + V(R).
//! The potential enters the equations through its left-trivialised gradient f(R) ∈ R³,
//! d/dε V(R exp(εζ̂)) = f(R)·ζ, and the Euler–Poincaré equations read
//! μ̇ = μ × Ω − f(R), Ṙ = R Ω̂ (ad*_Ω μ = μ × Ω on so(3)* ≅ R³).

use super::so3::{Mat3, cross, mul_tr_vec};
use crate::error::{GviError, Result};
use num_dual::DualNum;

/// A rigid body with a fixed point: principal moments of inertia and a potential on SO(3).
pub trait RigidBody: Sync {
    /// Short name for tables.
    fn name(&self) -> &'static str;

    /// Principal moments of inertia (I₁, I₂, I₃), the diagonal of 𝕀 in the body frame.
    fn inertia(&self) -> [f64; 3];

    /// V(R), generic over the scalar. Default: no potential (a free body).
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, _r: &Mat3<T>) -> T {
        T::from(0.0)
    }

    /// The left-trivialised gradient f(R) of V: d/dε V(R exp(εζ̂)) = f(R)·ζ. Default zero.
    fn torque<T: DualNum<Primitive = f64> + Copy>(&self, _r: &Mat3<T>) -> [T; 3] {
        [T::from(0.0); 3]
    }

    /// Whether V is not identically zero (the integrator skips the torque terms otherwise).
    fn has_potential(&self) -> bool {
        false
    }

    /// Body angular velocity Ω = 𝕀⁻¹μ.
    fn angular_velocity(&self, mu: &[f64; 3]) -> [f64; 3] {
        let i = self.inertia();
        [mu[0] / i[0], mu[1] / i[1], mu[2] / i[2]]
    }

    /// Energy ½ μ·𝕀⁻¹μ + V(R).
    fn energy(&self, r: &Mat3<f64>, mu: &[f64; 3]) -> f64 {
        let w = self.angular_velocity(mu);
        0.5 * (mu[0] * w[0] + mu[1] * w[1] + mu[2] * w[2]) + self.potential(r)
    }

    /// Right-hand side of the Euler–Poincaré equations: (Ṙ, μ̇) = (R Ω̂, μ × Ω − f(R)).
    fn vector_field(&self, r: &Mat3<f64>, mu: &[f64; 3]) -> (Mat3<f64>, [f64; 3]) {
        let w = self.angular_velocity(mu);
        let wh = super::so3::hat(&w);
        let rd = super::so3::mul(r, &wh);
        let f = self.torque(r);
        let c = cross(mu, &w);
        (rd, [c[0] - f[0], c[1] - f[1], c[2] - f[2]])
    }
}

fn check_inertia(inertia: [f64; 3]) -> Result<()> {
    for (k, &i) in inertia.iter().enumerate() {
        if !(i.is_finite() && i > 0.0) {
            return Err(GviError::InvalidParameter {
                name: format!("inertia[{k}]"),
                value: i,
                reason: "principal moments must be finite and positive".into(),
            });
        }
    }
    let [a, b, c] = inertia;
    if a > b + c || b > a + c || c > a + b {
        return Err(GviError::InvalidParameter {
            name: "inertia".into(),
            value: a.max(b).max(c),
            reason: "principal moments of a physical body obey the triangle inequality".into(),
        });
    }
    Ok(())
}

/// The free rigid body (Euler top): no potential.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeRigidBody {
    inertia: [f64; 3],
}

impl FreeRigidBody {
    /// A free body with principal moments `inertia`.
    pub fn new(inertia: [f64; 3]) -> Result<Self> {
        check_inertia(inertia)?;
        Ok(FreeRigidBody { inertia })
    }
}

impl RigidBody for FreeRigidBody {
    fn name(&self) -> &'static str {
        "rigid-body"
    }
    fn inertia(&self) -> [f64; 3] {
        self.inertia
    }
}

/// A heavy top (3D pendulum): a rigid body with a fixed point in uniform gravity,
/// V(R) = m g e₃·R χ with χ the body-frame vector from the fixed point to the centre of mass.
/// With I₁ = I₂ and χ on the third axis it is the Lagrange top; with an asymmetric inertia and
/// an off-axis χ it is the 3D pendulum of Lee, Leok & McClamroch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeavyTop {
    inertia: [f64; 3],
    /// m g (weight).
    weight: f64,
    /// Centre of mass in the body frame.
    com: [f64; 3],
}

impl HeavyTop {
    /// A heavy top with principal moments `inertia` (about the fixed point), mass `mass`,
    /// gravity `gravity` and centre of mass `com` (body frame).
    pub fn new(inertia: [f64; 3], mass: f64, gravity: f64, com: [f64; 3]) -> Result<Self> {
        check_inertia(inertia)?;
        for (name, v) in [("mass", mass), ("gravity", gravity)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(GviError::InvalidParameter {
                    name: name.into(),
                    value: v,
                    reason: "must be finite and non-negative".into(),
                });
            }
        }
        crate::error::ensure_finite("centre of mass", &com)?;
        Ok(HeavyTop {
            inertia,
            weight: mass * gravity,
            com,
        })
    }
}

impl RigidBody for HeavyTop {
    fn name(&self) -> &'static str {
        "heavy-top"
    }
    fn inertia(&self) -> [f64; 3] {
        self.inertia
    }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, r: &Mat3<T>) -> T {
        // e₃·Rχ = third row of R times χ.
        (r[2][0] * self.com[0] + r[2][1] * self.com[1] + r[2][2] * self.com[2]) * self.weight
    }
    fn torque<T: DualNum<Primitive = f64> + Copy>(&self, r: &Mat3<T>) -> [T; 3] {
        // d/dε m g e₃·R exp(εζ̂)χ = m g (Rᵀe₃)·(ζ × χ) = ζ·(m g χ × Rᵀe₃).
        let z = T::from(0.0);
        let gamma = mul_tr_vec(r, &[z, z, T::from(1.0)]);
        let chi = self.com.map(T::from);
        cross(&chi, &gamma).map(|c| c * self.weight)
    }
    fn has_potential(&self) -> bool {
        self.weight != 0.0 && self.com.iter().any(|&c| c != 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lie::so3::Retraction;

    #[test]
    fn heavy_top_torque_is_the_left_trivialised_gradient() {
        let top = HeavyTop::new([1.0, 1.5, 2.0], 2.0, 9.81, [0.1, -0.2, 0.5]).unwrap();
        let r: Mat3<f64> = Retraction::Exp.map(&[0.4, -1.1, 0.7]);
        let f = top.torque(&r);
        for k in 0..3 {
            let mut z = [0.0; 3];
            let e = 1e-6;
            z[k] = e;
            let rp = crate::lie::so3::mul(&r, &Retraction::Exp.map(&z));
            z[k] = -e;
            let rm = crate::lie::so3::mul(&r, &Retraction::Exp.map(&z));
            let fd = (top.potential(&rp) - top.potential(&rm)) / (2.0 * e);
            assert!((fd - f[k]).abs() < 1e-8, "{k}: {fd} vs {}", f[k]);
        }
    }

    #[test]
    fn bad_parameters_are_typed_errors() {
        assert!(FreeRigidBody::new([1.0, -1.0, 1.0]).is_err());
        assert!(FreeRigidBody::new([1.0, 1.0, 3.0]).is_err());
        assert!(HeavyTop::new([1.0, 1.0, 1.0], f64::NAN, 1.0, [0.0; 3]).is_err());
    }
}
