//! Osculating orbital elements: the longitude of perihelion of one body about another.

/// Longitude of periapsis ϖ = Ω + ω (radians, in (−π, π]) of the osculating two-body orbit of
/// relative position `r` and velocity `v` (3-D) with gravitational parameter `mu`, measured
/// in the reference frame's xy plane from the x axis (Ω: ascending node on the xy plane,
/// ω: from the node to the eccentricity vector in the orbital plane). For an orbit in the
/// xy plane (no node) ϖ is the angle of the eccentricity vector. `None` for degenerate states
/// (zero angular momentum or circular orbits, where ϖ is undefined).
///
/// ```
/// use galerkin_vi_lab::nbody_report::longitude_of_perihelion;
/// // Kepler e = 0.6 at periapsis on the +x axis: ϖ = 0.
/// let w = longitude_of_perihelion([0.4, 0.0, 0.0], [0.0, 2.0, 0.0], 1.0).unwrap();
/// assert!(w.abs() < 1e-15);
/// ```
pub fn longitude_of_perihelion(r: [f64; 3], v: [f64; 3], mu: f64) -> Option<f64> {
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let h = cross(r, v);
    let hn = dot(h, h).sqrt();
    let rn = dot(r, r).sqrt();
    if hn == 0.0 || rn == 0.0 || mu.is_nan() || mu <= 0.0 {
        return None;
    }
    let vh = cross(v, h);
    let e = [
        vh[0] / mu - r[0] / rn,
        vh[1] / mu - r[1] / rn,
        vh[2] / mu - r[2] / rn,
    ];
    if dot(e, e).sqrt() < 1e-12 {
        return None;
    }
    // Node vector ẑ × h; for an (almost) planar orbit fall back to the x axis.
    let node = [-h[1], h[0], 0.0];
    let nn = dot(node, node).sqrt();
    let (big_omega, n_hat) = if nn > 1e-12 * hn {
        (node[1].atan2(node[0]), [node[0] / nn, node[1] / nn, 0.0])
    } else {
        (0.0, [1.0, 0.0, 0.0])
    };
    let h_hat = [h[0] / hn, h[1] / hn, h[2] / hn];
    let omega = dot(cross(n_hat, e), h_hat).atan2(dot(n_hat, e));
    Some(wrap(big_omega + omega))
}

/// An angle reduced to (−π, π].
pub fn wrap(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut x = a % two_pi;
    if x > std::f64::consts::PI {
        x -= two_pi;
    } else if x <= -std::f64::consts::PI {
        x += two_pi;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotated_orbit_has_rotated_perihelion() {
        // The e = 0.6 orbit rotated by 0.7 rad about z, then tilted by 0.4 rad about the
        // line of apsides (which leaves the periapsis direction, hence ϖ, unchanged).
        let (c, s) = (0.7f64.cos(), 0.7f64.sin());
        let r = [0.4 * c, 0.4 * s, 0.0];
        let (ci, si) = (0.4f64.cos(), 0.4f64.sin());
        let v = [-2.0 * s * ci, 2.0 * c * ci, 2.0 * si];
        let w = longitude_of_perihelion(r, v, 1.0).unwrap();
        assert!((w - 0.7).abs() < 1e-14, "{w}");
        assert!(longitude_of_perihelion([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 1.0).is_none());
        assert!((wrap(4.0) - (4.0 - std::f64::consts::TAU)).abs() < 1e-15);
    }
}
