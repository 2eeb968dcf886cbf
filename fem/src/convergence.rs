//! Convergence criteria of the Newton iteration (Kratos' residual and displacement
//! criteria, and their combinations).
//!
//! At iteration `k` with residual `r_k = ‖R_k‖` (free equations), first residual `r_0`, last
//! correction `‖δu_k‖` and the step's accumulated increment `‖Δu‖`:
//!
//! - residual: `r_k ≤ ε_abs` or `r_k ≤ ε_rel r_0`;
//! - displacement: `‖δu_k‖ ≤ η_abs` or `‖δu_k‖ ≤ η_rel ‖Δu‖`;
//! - `and` (default), `or`, or either alone.
//!
//! A step whose first residual is already below `ε_abs` has converged without a solve. The
//! displacement criterion is known before assembling, and Newton's quadratic rate predicts
//! the next residual from the last two corrections, `r_k ≈ r_{k−1} (‖δu_k‖/‖δu_{k−1}‖)²`, so
//! the strategy can assemble the residual alone first when the step has most likely
//! converged ([`Convergence::likely`]).

use serde::Deserialize;

/// Which norms decide convergence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ConvergenceCriterion {
    /// Residual only.
    Residual,
    /// Displacement increment only.
    Displacement,
    /// Both (the default).
    #[default]
    And,
    /// Either.
    Or,
}

/// Norms per block of the monolithic system (soil, interface, structure).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BlockNorms {
    /// Equations of grid nodes.
    pub soil: f64,
    /// Equations of interface nodes (and of tied DOFs).
    pub interface: f64,
    /// Equations of structure nodes.
    pub structure: f64,
}

impl BlockNorms {
    /// The larger of each block's norms.
    pub fn max(self, o: Self) -> Self {
        Self {
            soil: self.soil.max(o.soil),
            interface: self.interface.max(o.interface),
            structure: self.structure.max(o.structure),
        }
    }
}

/// The criteria with their tolerances and the norms of the current step.
#[derive(Debug, Clone, Copy)]
pub struct Convergence {
    /// Combination of the criteria.
    pub criterion: ConvergenceCriterion,
    /// `ε_rel`.
    pub residual_relative: f64,
    /// `ε_abs` (N).
    pub residual_absolute: f64,
    /// `η_rel`.
    pub displacement_relative: f64,
    /// `η_abs` (m).
    pub displacement_absolute: f64,
    /// First residual of the step.
    r0: f64,
    /// Whether `r0` was given (an earlier solve's) rather than taken at iteration 0.
    fixed_r0: bool,
}

impl Convergence {
    /// Criteria with these tolerances, before the first residual of a step.
    pub fn new(
        criterion: ConvergenceCriterion,
        residual_relative: f64,
        residual_absolute: f64,
        displacement_relative: f64,
        displacement_absolute: f64,
    ) -> Self {
        Self {
            criterion,
            residual_relative,
            residual_absolute,
            displacement_relative,
            displacement_absolute,
            r0: 0.0,
            fixed_r0: false,
        }
    }

    /// Takes `r0` as the first residual of the step (from an earlier solve of it) instead of
    /// the residual at iteration 0.
    pub fn set_reference(&mut self, r0: f64) {
        self.r0 = r0;
        self.fixed_r0 = true;
    }

    /// The residual criterion at `r` (records `r_0` at iteration 0).
    fn residual_met(&mut self, iteration: usize, r: f64) -> bool {
        if iteration == 0 && !self.fixed_r0 {
            self.r0 = r;
        }
        r <= self.residual_absolute || r <= self.residual_relative * self.r0
    }

    /// Whether the residual criterion alone holds at `r` after iteration 0 (`r_0` recorded);
    /// under the `and` criterion a step can meet it while its last correction is still too
    /// large ([`crate::newton::TangentReuse::Finish`]).
    pub fn residual_criterion_met(&self, iteration: usize, r: f64) -> bool {
        iteration > 0 && (r <= self.residual_absolute || r <= self.residual_relative * self.r0)
    }

    /// The displacement criterion for the last correction `du` and the step's increment
    /// `du_step` (never at iteration 0: nothing has been solved).
    pub fn displacement_met(&self, iteration: usize, du: f64, du_step: f64) -> bool {
        self.displacement_within(1.0, iteration, du, du_step)
    }

    /// The displacement criterion with its tolerances widened by `factor`.
    pub fn displacement_within(&self, factor: f64, iteration: usize, du: f64, du_step: f64) -> bool {
        iteration > 0
            && (du <= factor * self.displacement_absolute || du <= factor * self.displacement_relative * du_step)
    }

    /// Whether iteration `iteration` with residual `r` has converged (see the module doc);
    /// `disp` is [`Convergence::displacement_met`] for the correction that led to this
    /// iteration as it was solved (before any line-search shortening: a correction cut
    /// short does not converge by being short).
    pub fn converged(&mut self, iteration: usize, r: f64, disp: bool) -> bool {
        let res = self.residual_met(iteration, r);
        if iteration == 0 {
            return r <= self.residual_absolute;
        }
        match self.criterion {
            ConvergenceCriterion::Residual => res,
            ConvergenceCriterion::Displacement => disp,
            ConvergenceCriterion::And => res && disp,
            ConvergenceCriterion::Or => res || disp,
        }
    }

    /// Whether the residual criterion will most likely hold at iteration `iteration`: the
    /// residual predicted by Newton's quadratic rate from the last residual `r_prev` and
    /// corrections `du`, `du_prev`, with a factor 2 to spare.
    pub fn residual_likely(&self, iteration: usize, r_prev: f64, du: f64, du_prev: f64) -> bool {
        iteration > 1 && {
            let predicted = r_prev * (du / du_prev).powi(2);
            predicted <= 0.5 * self.residual_absolute.max(self.residual_relative * self.r0)
        }
    }

    /// Whether iteration `iteration` will most likely converge: the displacement criterion,
    /// and the residual predicted from the last residual `r_prev` and corrections `du`,
    /// `du_prev` (trusted with a factor 2 to spare; a wrong guess costs one residual-only
    /// assembly).
    pub fn likely(&self, iteration: usize, r_prev: f64, du: f64, du_prev: f64, du_step: f64) -> bool {
        let disp = self.displacement_met(iteration, du, du_step);
        let residual = self.residual_likely(iteration, r_prev, du, du_prev);
        match self.criterion {
            ConvergenceCriterion::Residual => residual,
            ConvergenceCriterion::Displacement | ConvergenceCriterion::And => disp,
            ConvergenceCriterion::Or => disp || residual,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn criteria_combine_as_named() {
        let make = |c| Convergence::new(c, 1e-6, 1e-9, 1e-6, 1e-12);
        // residual met (1e-7 relative), displacement not (1e-3 relative)
        for (c, expected) in [
            (ConvergenceCriterion::Residual, true),
            (ConvergenceCriterion::Displacement, false),
            (ConvergenceCriterion::And, false),
            (ConvergenceCriterion::Or, true),
        ] {
            let mut conv = make(c);
            assert!(!conv.converged(0, 1.0, false));
            let disp = conv.displacement_met(1, 1e-3, 1.0);
            assert_eq!(conv.converged(1, 1e-7, disp), expected, "{c:?}");
        }
        // a first residual below the absolute tolerance converges without a solve
        assert!(make(ConvergenceCriterion::And).converged(0, 1e-10, false));
    }

    #[test]
    fn residual_alone_and_widened_displacement_criterion() {
        let mut conv = Convergence::new(ConvergenceCriterion::And, 1e-6, 1e-9, 1e-6, 1e-12);
        assert!(!conv.converged(0, 1.0, false));
        // r_0 = 1 recorded: the residual criterion alone, never at iteration 0
        assert!(conv.residual_criterion_met(2, 1e-7));
        assert!(!conv.residual_criterion_met(2, 1e-5));
        assert!(!conv.residual_criterion_met(0, 1e-10 * 0.5));
        // a correction 5e-5 of the step's increment: within 100 times the tolerance, not 10
        assert!(!conv.displacement_met(2, 5e-5, 1.0));
        assert!(conv.displacement_within(100.0, 2, 5e-5, 1.0));
        assert!(!conv.displacement_within(10.0, 2, 5e-5, 1.0));
    }
}
