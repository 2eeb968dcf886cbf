//! Time integration schemes: static (and quasi-static) load stepping, Newmark and Bossak.
//!
//! Newmark (1959): with `β`, `γ` and displacement `u_{n+1}` as the unknown,
//!
//! `a_{n+1} = (u_{n+1} − u_n − Δt v_n) / (β Δt²) − (1/(2β) − 1) a_n`,
//! `v_{n+1} = v_n + Δt ((1 − γ) a_n + γ a_{n+1})`.
//!
//! Bossak (Wood, Bossak & Zienkiewicz 1980) evaluates inertia at
//! `ã = (1 − α_B) a_{n+1} + α_B a_n` with `β = (1 − α_B)²/4`, `γ = 1/2 − α_B`, which damps
//! the highest frequencies for `α_B ∈ [−0.3, 0)`; Newmark is `α_B = 0`.
//! The equation solved is `M ã + f_int(u_{n+1}) = f_ext(t_{n+1})`, whose tangent is
//! `K_t + (1 − α_B)/(β Δt²) M`.

use serde::Deserialize;

use crate::domain::NodalState;

/// How time enters the equations of motion.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum TimeScheme {
    /// Equilibrium without inertia; time only scales loads (static and quasi-static).
    Static,
    /// Newmark with parameters β, γ (average acceleration: 0.25, 0.5).
    Newmark {
        /// β ∈ (0, 0.5].
        beta: f64,
        /// γ ∈ [0.5, 1].
        gamma: f64,
    },
    /// Bossak-α with β and γ derived from α for second-order accuracy.
    Bossak {
        /// α_B ∈ [−0.3, 0].
        alpha: f64,
    },
}

impl TimeScheme {
    /// `(α_B, β, γ)`, or `None` for a static scheme.
    pub fn coefficients(self) -> Option<(f64, f64, f64)> {
        match self {
            TimeScheme::Static => None,
            TimeScheme::Newmark { beta, gamma } => Some((0.0, beta, gamma)),
            TimeScheme::Bossak { alpha } => Some((alpha, 0.25 * (1.0 - alpha).powi(2), 0.5 - alpha)),
        }
    }

    /// Checks the parameter ranges.
    pub fn check(self) -> Result<(), (&'static str, String)> {
        match self {
            TimeScheme::Static => Ok(()),
            TimeScheme::Newmark { beta, gamma } => {
                if !(beta > 0.0 && beta <= 0.5) {
                    return Err(("beta", format!("must lie in (0, 0.5], got {beta}")));
                }
                if !(0.5..=1.0).contains(&gamma) {
                    return Err(("gamma", format!("must lie in [0.5, 1], got {gamma}")));
                }
                Ok(())
            }
            TimeScheme::Bossak { alpha } => {
                if !(-0.3..=0.0).contains(&alpha) {
                    return Err(("alpha", format!("must lie in [-0.3, 0], got {alpha}")));
                }
                Ok(())
            }
        }
    }

    /// Mass coefficient `c_M = (1 − α_B)/(β Δt²)` of the tangent (0 when static).
    pub fn mass_coefficient(self, dt: f64) -> f64 {
        match self.coefficients() {
            Some((alpha, beta, _)) => (1.0 - alpha) / (beta * dt * dt),
            None => 0.0,
        }
    }

    /// Updates `v` and `a` of one DOF from its displacement `u` (see the module doc);
    /// static schemes leave them untouched. Returns `(v, a)`.
    #[inline]
    pub fn kinematics(self, dt: f64, u: f64, un: f64, vn: f64, an: f64) -> (f64, f64) {
        match self.coefficients() {
            Some((_, beta, gamma)) => {
                let a = (u - un - dt * vn) / (beta * dt * dt) - (0.5 / beta - 1.0) * an;
                (vn + dt * ((1.0 - gamma) * an + gamma * a), a)
            }
            None => (vn, an),
        }
    }

    /// Acceleration at which inertia is evaluated, `ã = (1 − α_B) a_{n+1} + α_B a_n`.
    #[inline]
    pub fn inertial_acceleration(self, a: f64, an: f64) -> f64 {
        match self.coefficients() {
            Some((alpha, _, _)) => (1.0 - alpha) * a + alpha * an,
            None => 0.0,
        }
    }

    /// Newmark γ of the velocity update (½ for static schemes, where it is unused).
    pub fn gamma(self) -> f64 {
        self.coefficients().map_or(0.5, |c| c.2)
    }

    /// Whether the scheme carries inertia.
    pub fn is_dynamic(self) -> bool {
        self.coefficients().is_some()
    }

    /// Updates `v` and `a` of the first `dofs` DOFs of `state` (the displacement DOFs:
    /// pressures have no kinematics) from its displacement and the committed state
    /// ([`TimeScheme::kinematics`]).
    pub fn update_kinematics(self, dt: f64, state: &mut NodalState, committed: &NodalState, dofs: usize) {
        if !self.is_dynamic() {
            return;
        }
        for g in 0..dofs {
            let (v, a) = self.kinematics(dt, state.u[g], committed.u[g], committed.v[g], committed.a[g]);
            state.v[g] = v;
            state.a[g] = a;
        }
    }

    /// The accelerations `ã` at which inertia is evaluated, for every DOF.
    pub fn inertial_accelerations(self, state: &NodalState, committed: &NodalState, out: &mut [f64]) {
        for ((m, &a), &an) in out.iter_mut().zip(&state.a).zip(&committed.a) {
            *m = self.inertial_acceleration(a, an);
        }
    }
}
