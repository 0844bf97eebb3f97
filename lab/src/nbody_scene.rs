//! Building an [`NBody`] system and its initial state from a scene's `[[system.bodies]]`
//! ([`Body`], re-exported as `scene::Body`).

use crate::error::LabError;
use crate::error::Result;
use galerkin_vi::method::InitialState;
use galerkin_vi::systems::NBody;
use serde::{Deserialize, Serialize};

/// One body of an N-body scene: a name, exactly one of `mass` (with the system's G) or `gm`
/// (gravitational parameter; then G = 1 and GM is used as the mass, see
/// [`NBody::from_gm`](galerkin_vi::systems::NBody::from_gm)), position `q` and velocity `v`
/// (not momentum: p = m v is formed when the scene is loaded).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// Name, unique within the scene (e.g. `"Mercury"`).
    pub name: String,
    /// Mass (with the system's G).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// Gravitational parameter GM (G = 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gm: Option<f64>,
    /// Position (length `dim`).
    pub q: Vec<f64>,
    /// Velocity (length `dim`).
    pub v: Vec<f64>,
}

fn scene_error(reason: String) -> LabError {
    LabError::Scene {
        source_name: "[system] nbody".into(),
        reason,
    }
}

/// Validate the bodies, aggregate, move to the barycentre if asked, and build the system and
/// the initial state (p = m v). Every problem is a [`LabError::Scene`].
pub(crate) fn build(
    dim: usize,
    g: Option<f64>,
    aggregate: Option<&[String]>,
    barycentric: bool,
    bodies: &[Body],
) -> Result<(NBody, InitialState)> {
    if dim != 2 && dim != 3 {
        return Err(scene_error(format!("dim must be 2 or 3, got {dim}")));
    }
    if bodies.is_empty() {
        return Err(scene_error("no [[system.bodies]]".into()));
    }
    let uses_gm = bodies[0].gm.is_some();
    let mut names: Vec<String> = Vec::with_capacity(bodies.len());
    let mut masses = Vec::with_capacity(bodies.len());
    let (mut q, mut v) = (Vec::new(), Vec::new());
    for b in bodies {
        let m = match (b.mass, b.gm) {
            (Some(m), None) if !uses_gm => m,
            (None, Some(m)) if uses_gm => m,
            (Some(_), Some(_)) | (None, None) => {
                return Err(scene_error(format!(
                    "body '{}' needs exactly one of mass and gm",
                    b.name
                )));
            }
            _ => {
                return Err(scene_error(format!(
                    "body '{}': all bodies must give mass, or all gm",
                    b.name
                )));
            }
        };
        if !(m.is_finite() && m > 0.0) {
            let field = if uses_gm { "gm" } else { "mass" };
            return Err(scene_error(format!(
                "body '{}': {field} must be finite and positive, got {}",
                b.name,
                crate::error::fmt_number(m)
            )));
        }
        if b.q.len() != dim || b.v.len() != dim {
            return Err(scene_error(format!(
                "body '{}': q and v need {dim} components, got {} and {}",
                b.name,
                b.q.len(),
                b.v.len()
            )));
        }
        if b.q.iter().chain(&b.v).any(|x| !x.is_finite()) {
            return Err(scene_error(format!("body '{}': non-finite q or v", b.name)));
        }
        if names.contains(&b.name) {
            return Err(scene_error(format!("duplicate body name '{}'", b.name)));
        }
        names.push(b.name.clone());
        masses.push(m);
        q.extend_from_slice(&b.q);
        v.extend_from_slice(&b.v);
    }
    let g = match (g, uses_gm) {
        (Some(_), true) => {
            return Err(scene_error(
                "g must be omitted when bodies give gm (G = 1 is implied)".into(),
            ));
        }
        (Some(g), false) => g,
        (None, _) => 1.0,
    };
    if let Some(group) = aggregate {
        merge(dim, group, &mut names, &mut masses, &mut q, &mut v)?;
    }
    let system = NBody::new(masses, g, dim)
        .and_then(|s| s.with_names(names))
        .map_err(|e| scene_error(e.to_string()))?;
    if barycentric {
        system
            .to_barycentric(&mut q, &mut v)
            .map_err(|e| scene_error(e.to_string()))?;
    }
    let p = system.momenta(&v);
    Ok((system, InitialState { t0: 0.0, q, p }))
}

/// Merge the bodies named in `group` into one at their barycentre (total mass and momentum),
/// in the place of the first of them.
fn merge(
    dim: usize,
    group: &[String],
    names: &mut Vec<String>,
    masses: &mut Vec<f64>,
    q: &mut Vec<f64>,
    v: &mut Vec<f64>,
) -> Result<()> {
    if group.is_empty() {
        return Err(scene_error("aggregate lists no bodies".into()));
    }
    let mut idx = Vec::with_capacity(group.len());
    for name in group {
        let i = names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| scene_error(format!("aggregate: no body named '{name}'")))?;
        if idx.contains(&i) {
            return Err(scene_error(format!("aggregate: '{name}' listed twice")));
        }
        idx.push(i);
    }
    let total: f64 = idx.iter().map(|&i| masses[i]).sum();
    let (mut cq, mut cv) = (vec![0.0; dim], vec![0.0; dim]);
    for &i in &idx {
        for c in 0..dim {
            cq[c] += masses[i] * q[i * dim + c] / total;
            cv[c] += masses[i] * v[i * dim + c] / total;
        }
    }
    let first = idx[0];
    let merged_name = group.join("+");
    let (mut n2, mut m2, mut q2, mut v2) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for i in 0..names.len() {
        if i == first {
            n2.push(merged_name.clone());
            m2.push(total);
            q2.extend_from_slice(&cq);
            v2.extend_from_slice(&cv);
        } else if !idx.contains(&i) {
            n2.push(names[i].clone());
            m2.push(masses[i]);
            q2.extend_from_slice(&q[i * dim..(i + 1) * dim]);
            v2.extend_from_slice(&v[i * dim..(i + 1) * dim]);
        }
    }
    (*names, *masses, *q, *v) = (n2, m2, q2, v2);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use galerkin_vi::systems::System;

    fn body(name: &str, mass: f64, q: [f64; 2], v: [f64; 2]) -> Body {
        Body {
            name: name.into(),
            mass: Some(mass),
            gm: None,
            q: q.to_vec(),
            v: v.to_vec(),
        }
    }

    #[test]
    fn aggregation_conserves_mass_momentum_and_barycentre() {
        let bodies = [
            body("A", 1.0, [0.0, 0.0], [0.0, 0.0]),
            body("B", 3.0, [4.0, 0.0], [0.0, 1.0]),
            body("C", 1.0, [10.0, 0.0], [0.0, -1.0]),
        ];
        let group = ["A".to_string(), "B".to_string()];
        let (sys, init) = build(2, None, Some(&group), false, &bodies).unwrap();
        assert_eq!(sys.masses(), [4.0, 1.0]);
        assert_eq!(sys.names().unwrap(), ["A+B", "C"]);
        assert_eq!(init.q, [3.0, 0.0, 10.0, 0.0]);
        assert_eq!(init.p, [0.0, 3.0, 0.0, -1.0]);
        // Barycentric: total momentum and centre of mass vanish.
        let (sys, init) = build(2, Some(2.0), None, true, &bodies).unwrap();
        assert_eq!(sys.g(), 2.0);
        let mut inv = [0.0; 4];
        sys.invariants(&init.q, &init.p, &mut inv);
        assert!(inv[1].abs() < 1e-15 && inv[2].abs() < 1e-15);
        assert!(sys.centre_of_mass(&init.q).iter().all(|x| x.abs() < 1e-15));
    }

    #[test]
    fn malformed_bodies_are_scene_errors() {
        let good = body("A", 1.0, [0.0, 0.0], [0.0, 0.0]);
        let mut both = good.clone();
        both.gm = Some(1.0);
        let mut short = good.clone();
        short.q = vec![1.0];
        let mut negative = good.clone();
        negative.mass = Some(-1.0);
        let mut gm = body("B", 1.0, [1.0, 0.0], [0.0, 0.0]);
        (gm.mass, gm.gm) = (None, Some(1.0));
        let cases: Vec<(usize, Vec<Body>, Option<Vec<String>>)> = vec![
            (4, vec![good.clone()], None),
            (2, vec![], None),
            (2, vec![both], None),
            (2, vec![short], None),
            (2, vec![negative], None),
            (2, vec![good.clone(), good.clone()], None),
            (2, vec![good.clone(), gm], None),
            (2, vec![good.clone()], Some(vec!["Z".into()])),
            (2, vec![good.clone()], Some(vec!["A".into(), "A".into()])),
        ];
        for (dim, bodies, agg) in cases {
            let r = build(dim, None, agg.as_deref(), false, &bodies);
            assert!(matches!(r, Err(LabError::Scene { .. })), "{r:?}");
        }
    }
}
