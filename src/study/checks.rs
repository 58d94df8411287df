//! Checks of a value against a reference within a stated tolerance: the quick validation's and
//! the self-checks every run makes on its own answer (periodicity over a base pitch, balance,
//! the unloaded geometry's expectations).

use serde::Serialize;

/// One check: a value against its reference within a tolerance.
#[derive(Debug, Clone, Serialize)]
pub struct Check {
    pub study: &'static str,
    pub quantity: String,
    pub value: f64,
    pub reference: f64,
    pub reference_source: String,
    /// |value − reference| (absolute) or |value / reference − 1| (relative) at most this; for a
    /// ranking, value < reference.
    pub tolerance: f64,
    pub kind: CheckKind,
    pub passed: bool,
    /// A failed check that only makes the result suspicious (a warning), not wrong.
    pub warning_only: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CheckKind {
    Absolute,
    Relative,
    Below,
}

impl Check {
    /// This check as a warning: its failure flags the result as suspicious.
    pub fn warning(mut self) -> Self {
        self.warning_only = true;
        self
    }

    /// A failed check that makes the result wrong.
    pub fn is_error(&self) -> bool {
        !self.passed && !self.warning_only
    }

    /// One line: what, value against reference, tolerance, verdict.
    pub fn line(&self) -> String {
        let verdict = match (self.passed, self.warning_only) {
            (true, _) => "ok",
            (false, true) => "WARNING",
            (false, false) => "FAILED",
        };
        let rule = match self.kind {
            CheckKind::Absolute => format!("absolute, tolerance {:.1e}", self.tolerance),
            CheckKind::Relative => format!("relative, tolerance {:.1e}", self.tolerance),
            CheckKind::Below if self.tolerance > 0.0 => {
                format!("below by {:.1e} of it", self.tolerance)
            }
            CheckKind::Below => "below it".to_string(),
        };
        format!(
            "{verdict}: {}: {:.4e} against {:.4e} ({rule}; {})",
            self.quantity, self.value, self.reference, self.reference_source
        )
    }

    pub fn new(
        study: &'static str,
        quantity: impl Into<String>,
        (value, reference): (f64, f64),
        reference_source: impl Into<String>,
        (kind, tolerance): (CheckKind, f64),
    ) -> Self {
        let passed = match kind {
            CheckKind::Absolute => (value - reference).abs() <= tolerance,
            CheckKind::Relative => (value / reference - 1.0).abs() <= tolerance,
            // Below by at least the tolerance's share of the reference.
            CheckKind::Below => value < reference * (1.0 - tolerance),
        };
        Check {
            study,
            quantity: quantity.into(),
            value,
            reference,
            reference_source: reference_source.into(),
            tolerance,
            kind,
            passed,
            warning_only: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each rule passes inside its tolerance and fails outside it.
    #[test]
    fn checks_pass_inside_and_fail_outside_their_tolerance() {
        let check = |pair, rule| Check::new("t", "q", pair, "r", rule).passed;
        assert!(check((1.694, 1.69), (CheckKind::Absolute, 0.005)));
        assert!(!check((1.696, 1.69), (CheckKind::Absolute, 0.005)));
        assert!(check((100.4, 100.0), (CheckKind::Relative, 0.005)));
        assert!(!check((100.6, 100.0), (CheckKind::Relative, 0.005)));
        assert!(!check((99.4, 100.0), (CheckKind::Relative, 0.005)));
        assert!(check((0.8, 1.3), (CheckKind::Below, 0.0)));
        assert!(!check((1.3, 1.3), (CheckKind::Below, 0.0)));
        assert!(check((0.89, 1.0), (CheckKind::Below, 0.1)));
        assert!(!check((0.91, 1.0), (CheckKind::Below, 0.1)));
    }
}
