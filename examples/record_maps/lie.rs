//! Lie group runs on SO(3): the free rigid body and the heavy top.

use super::*;

fn lie_tokens(line: &mut String, traj: &LieTrajectory) {
    let steps = traj.states.len() - 1;
    for (name, k) in [("mid", steps / 2), ("end", steps)] {
        let s = &traj.states[k];
        let r: Vec<f64> = s.r.iter().flatten().copied().collect();
        push_vector(line, &format!("R_{name}"), &r);
        push_vector(line, &format!("mu_{name}"), &s.mu);
    }
}

fn lie_run<S: RigidBody>(
    out: &mut Vec<String>,
    (system, body): (&str, &S),
    (basis, n, h, steps): (BasisKind, usize, f64, usize),
    retraction: Retraction,
    (r0, mu0): (&Mat3<f64>, &[f64; 3]),
) {
    let id = format!(
        "lie/{system}/{}/n{n}/gauss-legendre:default/h{h}/s{steps}/{}",
        basis.as_str(),
        retraction.as_str()
    );
    let line = match LieGalerkin::from_kinds(basis, n, QuadratureKind::GaussLegendre, None, h) {
        Ok(lie) => match lie
            .with_retraction(retraction)
            .integrate(body, 0.0, r0, mu0, steps)
        {
            Ok(traj) => {
                let mut line = format!("{id} ok");
                lie_tokens(&mut line, &traj);
                line
            }
            Err(e) => error_line(&id, "integrate", &e),
        },
        Err(e) => error_line(&id, "construct", &e),
    };
    out.push(line);
}

/// The Lie group integrator on SO(3): the free rigid body of scenes/rigid-body.toml (a quarter
/// period per step) and the heavy top of scenes/heavy-top.toml.
pub(super) fn lie_cases(out: &mut Vec<String>) -> Res<()> {
    let free = FreeRigidBody::new([1.0, 2.0, 3.0])?;
    let r0 = Retraction::Exp.map(&[0.3, -0.4, 0.2]);
    let mu0 = [1.0, 0.4, 3.0];
    let quarter = 1.7278907507449373;
    for (basis, retraction) in [
        (BasisKind::Legendre, Retraction::Exp),
        (BasisKind::Chebyshev, Retraction::Exp),
        (BasisKind::Legendre, Retraction::Cayley),
    ] {
        lie_run(
            out,
            ("rigid-body", &free),
            (basis, 16, quarter, 16),
            retraction,
            (&r0, &mu0),
        );
    }
    let top = HeavyTop::new([1.0, 1.0, 0.5], 1.0, 9.81, [0.0, 0.0, 0.5])?;
    let r0 = Retraction::Exp.map(&[0.5, 0.0, 0.0]);
    lie_run(
        out,
        ("heavy-top", &top),
        (BasisKind::Legendre, 12, 0.1, 40),
        Retraction::Exp,
        (&r0, &[0.0, 0.0, 5.0]),
    );
    Ok(())
}
