use galerkin_vi::prelude::*;
use galerkin_vi::lagrangian::Mechanical;
use nalgebra::DMatrix;
use num_dual::DualNum;
struct KDD;
impl Mechanical for KDD {
    fn degrees_of_freedom(&self) -> usize { 2 }
    fn mass(&self) -> DMatrix<f64> { DMatrix::identity(2, 2) }
    fn potential<T: DualNum<Primitive = f64> + Copy>(&self, q: &[T]) -> T { -(q[0] * q[0] + q[1] * q[1]).sqrt().recip() }
    fn potential_gradient(&self, q: &[f64], out: &mut [f64]) {
        let (x, y) = (DD(q[0], 0.0), DD(q[1], 0.0));
        let r2 = add(mul(x, x), mul(y, y));
        let r = sqrt(r2);
        let r3 = mul(r2, r);
        let k = div(DD(1.0, 0.0), r3);
        out[0] = mul(k, x).0 + mul(k, x).1;
        out[1] = mul(k, y).0 + mul(k, y).1;
    }
    fn potential_hessian(&self, q: &[f64], out: &mut [f64]) {
        let r2 = q[0] * q[0] + q[1] * q[1];
        let r3 = r2 * r2.sqrt();
        let a = 1.0 / r3;
        let b = 3.0 * a / r2;
        out[0] = a - b * q[0] * q[0];
        out[1] = -b * q[0] * q[1];
        out[2] = out[1];
        out[3] = a - b * q[1] * q[1];
    }
}
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args[1].parse().unwrap();
    let h: f64 = args[2].parse().unwrap();
    let horizon: f64 = args[3].parse().unwrap();
    let reps: usize = args[4].parse().unwrap();
    let tol: f64 = std::env::var("GVI_TOL").ok().and_then(|s| s.parse().ok()).unwrap_or(1e-18);
    let comp = std::env::var("GVI_PLAIN").is_err();
    let kepler = Kepler::new(1.0).unwrap();
    let (q00, p00) = Kepler::paper_initial_state();
    let gvi = GalerkinIntegrator::from_kinds(BasisKind::Legendre, n, QuadratureKind::GaussLegendre, std::env::var("M").ok().and_then(|s| s.parse().ok()), h)
        .unwrap()
        .with_options(NewtonOptions { tolerance: tol,
            floor_tolerance: std::env::var("GVI_FLOOR").ok().and_then(|s| s.parse().ok()).unwrap_or(1e-10),
            reuse_jacobian: std::env::var("GVI_NO_REUSE").is_err(),
            max_iterations: 60,
            ..NewtonOptions::default() });
    let steps = (horizon / h) as usize;
    let (mut se, mut sq) = (0.0, 0.0);
    for rep in 0..reps {
        let mut q0 = q00.to_vec();
        q0[0] += rep as f64 * 1e-9;
        let mut p0 = p00.to_vec();
        if let Ok(v) = std::env::var("P0") { let v: f64 = v.parse().unwrap(); q0[0] = 1.0 + rep as f64 * 1e-9; p0[1] = v; }
        let exact = kepler.exact_solution(0.0, &q0, &p0).unwrap().unwrap();
        let mut ws = gvi.workspace(&kepler).unwrap();
        let (mut q, mut p) = (q0.clone(), p0.clone());
        let (mut qe, mut pe) = (vec![0.0; 2], vec![0.0; 2]);
        let mut qn = vec![0.0; 2]; let mut pn = vec![0.0; 2];
        let en = |q: &[f64], p: &[f64], qe: &[f64], pe: &[f64]| { let (a, b) = energy_dd(q, p, qe, pe); a + b };
        let e0 = en(&q, &p, &qe, &pe);
        let mut emean = 0.0; let mut cnt = 0.0; let mut early = 0.0;
        let mut maxerr = 0.0f64;
        for k in 0..steps {
            if std::env::var("KDD").is_ok() {
                gvi.step_compensated(&KDD, &mut ws, &mut q, &mut qe, &mut p, &mut pe).unwrap();
            } else if comp {
                gvi.step_compensated(&kepler, &mut ws, &mut q, &mut qe, &mut p, &mut pe).unwrap();
            } else {
                gvi.step(&kepler, &mut ws, &q, &p, &mut qn, &mut pn).unwrap();
                q.copy_from_slice(&qn); p.copy_from_slice(&pn);
            }
            let t = (k + 1) as f64 * h;
            let w = (62.83185307179586 / h) as usize;
            if k + 1 > steps - w { emean += en(&q, &p, &qe, &pe) - e0; cnt += 1.0; }
            if k < w { early += en(&q, &p, &qe, &pe) - e0; }
            if ((k + 1) as f64 * h / 2.0).fract() == 0.0 {
                let x = exact.position(t);
                maxerr = maxerr.max((q[0] - x[0]).abs().max((q[1] - x[1]).abs()));
            }
        }
        emean = (emean - early) / cnt;
        se += emean * emean; sq += maxerr * maxerr;
        eprintln!("  rep {rep}: dE(T) {emean:.3e} maxerr {maxerr:.3e}");
    }
    println!("n={n} h={h} T={horizon}: rms dE(T) {:.3e}, rms maxerr {:.3e}", (se / reps as f64).sqrt(), (sq / reps as f64).sqrt());
}

#[derive(Clone, Copy)]
struct DD(f64, f64);
fn two_sum(a: f64, b: f64) -> DD { let s = a + b; let bb = s - a; DD(s, (a - (s - bb)) + (b - bb)) }
fn add(a: DD, b: DD) -> DD { let s = two_sum(a.0, b.0); let lo = s.1 + a.1 + b.1; two_sum(s.0, lo) }
fn mul(a: DD, b: DD) -> DD { let p = a.0 * b.0; let e = a.0.mul_add(b.0, -p); let lo = e + a.0 * b.1 + a.1 * b.0; two_sum(p, lo) }
fn div(a: DD, b: DD) -> DD { let q1 = a.0 / b.0; let r = add(a, DD(-mul(DD(q1, 0.0), b).0, -mul(DD(q1, 0.0), b).1)); let q2 = r.0 / b.0; two_sum(q1, q2) }
fn sqrt(a: DD) -> DD { let x = a.0.sqrt(); let xx = mul(DD(x, 0.0), DD(x, 0.0)); let r = add(a, DD(-xx.0, -xx.1)); two_sum(x, r.0 / (2.0 * x)) }
fn energy_dd(q: &[f64], p: &[f64], qe: &[f64], pe: &[f64]) -> (f64, f64) {
    let (x, y) = (DD(q[0], qe[0]), DD(q[1], qe[1]));
    let (u, v) = (DD(p[0], pe[0]), DD(p[1], pe[1]));
    let ke = mul(DD(0.5, 0.0), add(mul(u, u), mul(v, v)));
    let r = sqrt(add(mul(x, x), mul(y, y)));
    let pot = div(DD(1.0, 0.0), r);
    let e = add(ke, DD(-pot.0, -pot.1));
    (e.0, e.1)
}
