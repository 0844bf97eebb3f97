use super::*;

#[test]
fn placeholder_compiles() {
    let l = ExpressionLagrangian::parse("x_dot^2/2 - x^2/2", &["x"], &[]).unwrap();
    assert_eq!(l.dim(), 1);
}
