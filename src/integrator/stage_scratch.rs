//! Scratch of the stage equations: the Galerkin curve and the Lagrangian's derivatives at the
//! quadrature nodes, the action gradient ∂S/∂Q assembled from them, and the small buffers of
//! their products (docs/DESIGN.md §2).
//!
//! Written by every evaluation of the discrete action's derivatives
//! ([`super::discrete_action`]) and read by the residual, the Newton matrix, the structured
//! solvers and the Legendre-transform rows. Nothing here outlives one evaluation except two
//! facts about it, which are private and kept by methods: whether `hall` holds the node
//! Jacobians at the current curve ([`StageScratch::evaluate_node_jacobians`]) and whether the
//! curve is the candidate guess's. The buffers are the evaluation kernels' operands, not
//! solver state (the state is in [`super::iterate`], [`super::newton_system`] and the guess
//! module); all of them are sized once, by [`StageScratch::new`], so that a step allocates
//! nothing.

/// Node values, derivatives and products of one evaluation of the stage equations
/// (m quadrature nodes, n basis functions, D coordinates).
#[derive(Debug, Clone)]
pub(crate) struct StageScratch {
    /// Curve values q(c_j) at the quadrature nodes (m×D).
    pub qj: Vec<f64>,
    /// Curve velocities q̇(c_j) (m×D); separable Lagrangians skip them unless asked.
    pub vj: Vec<f64>,
    /// L_q at the nodes (m×D).
    pub lq: Vec<f64>,
    /// L_v at the nodes (m×D).
    pub lv: Vec<f64>,
    /// Whether the last curve evaluation used the Newton state's candidate (else its iterate).
    curve_from_cand: bool,
    /// ∂S/∂Q_a for every a (n×D).
    pub grad: Vec<f64>,
    /// Weighted forces h b_j L_q(c_j) (m×D).
    pub scaled: Vec<f64>,
    /// M (Q_b − u_b q_k) for the separable residual (n×D).
    pub mq: Vec<f64>,
    /// L_qq at every node (m×D×D).
    pub hall: Vec<f64>,
    /// `hall` is not at the iterate of the last freeze (which formed only diagonal blocks).
    hall_stale: bool,
    /// Diagonal b×b blocks of the node force Jacobians (m·D·b), when the system provides them
    /// and the frozen-Hessian preconditioner uses only those; empty otherwise.
    pub hblocks: Vec<f64>,
    /// The weighted basis table of one Gram product (n×m).
    pub gram: Vec<f64>,
    /// One (n−1)×(n−1) block of the Newton matrix.
    pub block: Vec<f64>,
    /// Non-separable Lagrangians: the node second derivatives (m × 4 × D², see
    /// [`super::node_model`]), for matrix-free Jacobian products; empty otherwise.
    pub node_hessians: Vec<f64>,
    /// Four D-vectors of scratch for those products (empty for separable Lagrangians).
    pub jvp_scratch: Vec<f64>,
    /// Non-separable Lagrangians: the Newton matrix's weighted node blocks (m × 4 × D²), one
    /// column coordinate's row side Z_sᵀ (2m × (n−1)D), the node table Ψᵀ ((n−1) × 2m) and
    /// the product Ψᵀ Z_sᵀ ((n−1) × (n−1)D) of `stage::general_blocks`; empty otherwise.
    pub jac_nodes: Vec<f64>,
    /// See `jac_nodes`.
    pub jac_rows: Vec<f64>,
    /// See `jac_nodes`.
    pub jac_psi: Vec<f64>,
    /// See `jac_nodes`.
    pub jac_block: Vec<f64>,
    /// L_qq, L_qv, L_vv at one node (D×D each).
    pub hqq: Vec<f64>,
    /// See `hqq`.
    pub hqv: Vec<f64>,
    /// See `hqq`.
    pub hvv: Vec<f64>,
    /// ∂L_v/∂q at one node (D×D): L_qv transposed, or with forcing the block that ∂f/∂v does
    /// not enter (see [`super::node_model`]).
    pub hvq: Vec<f64>,
    /// The force f at one node (D) and its Jacobians ∂f/∂q, ∂f/∂v (D×D each).
    pub fj: Vec<f64>,
    /// See `fj`.
    pub fq: Vec<f64>,
    /// See `fj`.
    pub fv: Vec<f64>,
    /// The node times t_k + c_j h of the step (m), which non-autonomous and forced systems are
    /// evaluated at; see [`StageScratch::set_step_start`].
    pub tj: Vec<f64>,
    /// The step's start time t_k.
    step_start: f64,
    /// The system depends on t explicitly or is forced: the nodes take the `_at` evaluations.
    timed: bool,
    /// A non-conservative force acts: f is added to L_q at the nodes.
    forced: bool,
    /// Double-double accumulators, one pair per coordinate (D each).
    pub dd_hi: Vec<f64>,
    /// See `dd_hi`.
    pub dd_lo: Vec<f64>,
    /// A velocity (D), e.g. of an inverse Legendre transform.
    pub vel: Vec<f64>,
    /// A small D×D solver (inverse Legendre transforms) with its right-hand side and scratch.
    pub small: crate::linalg::Lu,
    /// See `small`.
    pub small_rhs: Vec<f64>,
    /// See `small`.
    pub small_scratch: Vec<f64>,
}

impl StageScratch {
    /// L_qq at every node of the curve in `qj` into `hall`, which is then current.
    pub(crate) fn evaluate_node_jacobians<L: crate::lagrangian::Lagrangian>(&mut self, lag: &L) {
        lag.force_jacobian_at_points(&self.qj, &mut self.hall);
        self.hall_stale = false;
    }

    /// Only the diagonal b×b blocks of L_qq at the nodes into `hblocks`, when the workspace
    /// keeps them and the system provides them (else false, nothing done); `hall` is then
    /// not current.
    pub(crate) fn evaluate_node_jacobian_blocks<L: crate::lagrangian::Lagrangian>(
        &mut self,
        lag: &L,
    ) -> bool {
        let done = !self.hblocks.is_empty()
            && lag.force_jacobian_diagonal_blocks_at_points(&self.qj, &mut self.hblocks);
        if done {
            self.hall_stale = true;
        }
        done
    }

    /// Whether `hall` holds the node Jacobians at the curve in `qj` (not only their blocks).
    pub(crate) fn node_jacobians_current(&self) -> bool {
        !self.hall_stale
    }

    /// Record whether the curve in `qj` is the candidate guess's (else the iterate's).
    pub(crate) fn set_curve_of_candidate(&mut self, candidate: bool) {
        self.curve_from_cand = candidate;
    }

    /// Whether the curve in `qj` is the candidate guess's (else the iterate's).
    pub(crate) fn curve_of_candidate(&self) -> bool {
        self.curve_from_cand
    }
    /// Mark the system as time-dependent (`timed`) and forced (`forced`), once, when the
    /// workspace is made.
    pub(crate) fn set_time_dependence(&mut self, timed: bool, forced: bool) {
        self.timed = timed || forced;
        self.forced = forced;
    }

    /// Whether the node evaluations need the node times (time-dependent or forced system).
    pub(crate) fn timed(&self) -> bool {
        self.timed
    }

    /// Whether a non-conservative force acts.
    pub(crate) fn forced(&self) -> bool {
        self.forced
    }

    /// The step's start time t_k and the node times t_k + c_j h.
    pub(crate) fn set_step_start(&mut self, t: f64, h: f64, nodes: &[f64]) {
        self.step_start = t;
        for (tj, c) in self.tj.iter_mut().zip(nodes) {
            *tj = t + c * h;
        }
    }

    /// The step's start time t_k.
    pub(crate) fn step_start(&self) -> f64 {
        self.step_start
    }

    /// q_j ← q_j + q_k at every node: the curve's constant part added last, after the small
    /// parts (increments and compensation terms), so that they are not rounded away.
    pub(crate) fn add_to_nodes(&mut self, base: &[f64]) {
        for row in self.qj.chunks_exact_mut(base.len()) {
            for (x, b) in row.iter_mut().zip(base) {
                *x += b;
            }
        }
    }

    /// Buffers for n basis functions, m nodes, D coordinates; `general`: the Lagrangian is not
    /// separable (node Hessians are kept); `block_entries`: size of `hblocks` (0: unused).
    pub(crate) fn new(n: usize, m: usize, d: usize, general: bool, block_entries: usize) -> Self {
        let general_buffer = |len: usize| if general { vec![0.0; len] } else { Vec::new() };
        StageScratch {
            qj: vec![0.0; m * d],
            vj: vec![0.0; m * d],
            lq: vec![0.0; m * d],
            lv: vec![0.0; m * d],
            curve_from_cand: false,
            grad: vec![0.0; n * d],
            scaled: vec![0.0; m * d],
            mq: vec![0.0; n * d],
            hall: vec![0.0; m * d * d],
            hall_stale: true,
            hblocks: vec![0.0; block_entries],
            gram: vec![0.0; n * m],
            block: vec![0.0; n * n],
            node_hessians: if general {
                vec![0.0; 4 * m * d * d]
            } else {
                Vec::new()
            },
            jvp_scratch: if general {
                vec![0.0; 4 * d]
            } else {
                Vec::new()
            },
            jac_nodes: general_buffer(4 * m * d * d),
            jac_rows: general_buffer(n.saturating_sub(1) * d * 2 * m),
            jac_psi: general_buffer(2 * m * n.saturating_sub(1)),
            jac_block: general_buffer(n.saturating_sub(1) * d * n.saturating_sub(1)),
            hqq: vec![0.0; d * d],
            hqv: vec![0.0; d * d],
            hvv: vec![0.0; d * d],
            hvq: vec![0.0; d * d],
            fj: vec![0.0; d],
            fq: vec![0.0; d * d],
            fv: vec![0.0; d * d],
            tj: vec![0.0; m],
            step_start: 0.0,
            timed: false,
            forced: false,
            dd_hi: vec![0.0; d],
            dd_lo: vec![0.0; d],
            vel: vec![0.0; d],
            small: crate::linalg::Lu::with_capacity(d),
            small_rhs: vec![0.0; d],
            small_scratch: vec![0.0; d],
        }
    }
}
