//! [`Decision`]: one thing a render runs or leaves out, and why (what `vcm render --explain`
//! prints).

use std::fmt;

/// Whether one part of the work runs for a scene, and the reason.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Decision {
    /// The part of the work, e.g. "hash grid".
    pub part: &'static str,
    /// Whether it runs.
    pub runs: bool,
    /// Why it runs or is left out, in terms of the scene or the settings.
    pub reason: String,
}

impl Decision {
    /// A part that runs because of `reason`.
    pub fn runs(part: &'static str, reason: impl Into<String>) -> Decision {
        Decision {
            part,
            runs: true,
            reason: reason.into(),
        }
    }

    /// A part that is left out because of `reason`.
    pub fn left_out(part: &'static str, reason: impl Into<String>) -> Decision {
        Decision {
            part,
            runs: false,
            reason: reason.into(),
        }
    }
}

impl fmt::Display for Decision {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let verdict = if self.runs { "runs" } else { "left out" };
        write!(f, "{}: {verdict} ({})", self.part, self.reason)
    }
}
