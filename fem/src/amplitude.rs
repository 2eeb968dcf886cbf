//! Time functions that scale loads and prescribed values.

use serde::Deserialize;

/// A multiplier `f(t)`: a constant, or a table of `[t, f]` pairs interpolated linearly
/// and held constant outside its range. In case files: `1.0` or `[[0, 0], [1, 1]]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Amplitude {
    /// Constant factor.
    Constant(f64),
    /// Piecewise-linear table of `[time, factor]`, times increasing.
    Table(Vec<[f64; 2]>),
}

impl Default for Amplitude {
    fn default() -> Self {
        Amplitude::Constant(1.0)
    }
}

impl Amplitude {
    /// Value at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        match self {
            Amplitude::Constant(c) => *c,
            Amplitude::Table(rows) => {
                let Some(first) = rows.first() else { return 0.0 };
                if t <= first[0] {
                    return first[1];
                }
                for w in rows.windows(2) {
                    if t <= w[1][0] {
                        let s = (t - w[0][0]) / (w[1][0] - w[0][0]);
                        return (1.0 - s) * w[0][1] + s * w[1][1]; // exact at the table times
                    }
                }
                rows.last().map(|r| r[1]).unwrap_or(0.0)
            }
        }
    }

    /// Checks a table: at least one row, strictly increasing times, finite values.
    pub fn check(&self) -> Result<(), String> {
        match self {
            Amplitude::Constant(c) if !c.is_finite() => Err(format!("must be finite, got {c}")),
            Amplitude::Constant(_) => Ok(()),
            Amplitude::Table(rows) => {
                if rows.is_empty() {
                    return Err("table needs at least one [time, factor] row".into());
                }
                if rows.iter().flatten().any(|v| !v.is_finite()) {
                    return Err("table values must be finite".into());
                }
                if rows.windows(2).any(|w| w[1][0] <= w[0][0]) {
                    return Err("table times must increase strictly".into());
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_interpolates_and_holds() {
        let a = Amplitude::Table(vec![[0.0, 0.0], [1.0, 2.0], [2.0, 2.0]]);
        assert_eq!(a.at(-1.0), 0.0);
        assert_eq!(a.at(0.5), 1.0);
        assert_eq!(a.at(5.0), 2.0);
        assert!(Amplitude::Table(vec![[1.0, 0.0], [1.0, 1.0]]).check().is_err());
    }
}
