//! `YarnSet`: the curves of a yarn model, optionally periodic (a patch that tiles the plane
//! with period `[px, py]`).

use super::YarnCurve;
use crate::{Error, Result};

/// A set of yarn curves, optionally periodic with period `[px, py]` (metres) in x and y.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct YarnSet {
    /// The curves.
    pub curves: Vec<YarnCurve>,
    /// The period of a periodic patch (the set is invariant under translation by
    /// `(px, 0, 0)` and `(0, py, 0)`).
    pub period: Option<[f64; 2]>,
}

impl YarnSet {
    /// A validated set.
    pub fn new(curves: Vec<YarnCurve>, period: Option<[f64; 2]>) -> Result<Self> {
        let s = YarnSet { curves, period };
        s.validate()?;
        Ok(s)
    }

    /// Checks every curve (the error names the curve index) and the period.
    pub fn validate(&self) -> Result<()> {
        if let Some([px, py]) = self.period
            && !(px.is_finite() && py.is_finite() && px > 0.0 && py > 0.0)
        {
            return Err(Error::Invalid(format!(
                "yarn set period [{px}, {py}] must be finite and positive"
            )));
        }
        for (i, c) in self.curves.iter().enumerate() {
            c.validate(i)?;
        }
        Ok(())
    }
}
