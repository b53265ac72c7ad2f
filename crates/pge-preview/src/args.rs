//! The preview's command-line values (`pge preview`'s `--lod-level`, `--leaf-budget`,
//! `--camera`), parsed into their types or refused with an [`ArgError`] that says what is
//! expected.

use crate::CameraSpec;
use crate::forest::LEAF_BUDGETS;

/// A command-line value the preview refuses.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ArgError {
    /// `--lod-level`: not a fraction of the leaves between 0.01 and 1.
    #[error("'{0}' is not a fraction between 0.01 and 1")]
    Fraction(String),
    /// `--leaf-budget`: not a whole number of leaves in [`LEAF_BUDGETS`].
    #[error(
        "'{0}' is not a number of leaves between {least} and {most}",
        least = LEAF_BUDGETS.start(),
        most = LEAF_BUDGETS.end()
    )]
    LeafBudget(String),
    /// `--camera`: not `D,H` or `D,H,TX,TY,TZ` (finite numbers, `D > 0`).
    #[error("'{0}' is not D,H or D,H,TX,TY,TZ (numbers, D > 0)")]
    Camera(String),
}

/// Parses `--lod-level`: a fraction of the leaves between 0.01 and 1.
pub fn parse_fraction(text: &str) -> Result<f64, ArgError> {
    match text.trim().parse::<f64>() {
        Ok(f) if (0.01..=1.0).contains(&f) => Ok(f),
        _ => Err(ArgError::Fraction(text.to_string())),
    }
}

/// Parses `--leaf-budget`: a whole number of leaves in [`LEAF_BUDGETS`].
pub fn parse_budget(text: &str) -> Result<u64, ArgError> {
    match text.trim().parse::<u64>() {
        Ok(n) if LEAF_BUDGETS.contains(&n) => Ok(n),
        _ => Err(ArgError::LeafBudget(text.to_string())),
    }
}

/// Parses `--camera D,H[,TX,TY,TZ]`: numbers, `D > 0`.
pub fn parse_camera(text: &str) -> Result<CameraSpec, ArgError> {
    let bad = || ArgError::Camera(text.to_string());
    let numbers = text
        .split(',')
        .map(|s| s.trim().parse::<f32>().ok().filter(|v| v.is_finite()))
        .collect::<Option<Vec<f32>>>()
        .ok_or_else(bad)?;
    let target = match numbers.len() {
        2 => None,
        5 => Some(glam::Vec3::new(numbers[2], numbers[3], numbers[4])),
        _ => return Err(bad()),
    };
    if numbers[0] <= 0.0 {
        return Err(bad());
    }
    Ok(CameraSpec {
        distance: numbers[0],
        height: numbers[1],
        target,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fractions_are_parsed() {
        assert_eq!(parse_fraction("0.5"), Ok(0.5));
        assert_eq!(parse_fraction(" 1 "), Ok(1.0));
        assert_eq!(parse_fraction("0.01"), Ok(0.01));
        for bad in ["0", "0.009", "1.5", "-0.5", "x", "NaN", ""] {
            assert_eq!(
                parse_fraction(bad),
                Err(ArgError::Fraction(bad.to_string())),
                "{bad}"
            );
        }
        assert_eq!(
            parse_fraction("2").expect_err("refused").to_string(),
            "'2' is not a fraction between 0.01 and 1"
        );
    }

    #[test]
    fn budgets_are_parsed() {
        assert_eq!(parse_budget("2000000"), Ok(2_000_000));
        assert_eq!(parse_budget(" 100 "), Ok(100));
        for bad in ["99", "0", "-5", "1e6", "x", "100000001"] {
            assert_eq!(
                parse_budget(bad),
                Err(ArgError::LeafBudget(bad.to_string())),
                "{bad}"
            );
        }
        assert_eq!(
            parse_budget("99").expect_err("refused").to_string(),
            "'99' is not a number of leaves between 100 and 100000000"
        );
    }

    #[test]
    fn camera_placements_are_parsed() {
        assert_eq!(
            parse_camera("2,1.5"),
            Ok(CameraSpec {
                distance: 2.0,
                height: 1.5,
                target: None
            })
        );
        assert_eq!(
            parse_camera("30, 8, 0, -1, 2.5").map(|c| c.target),
            Ok(Some(glam::Vec3::new(0.0, -1.0, 2.5)))
        );
        for bad in ["2", "2,1,0", "0,1", "-1,2", "a,b", "2,NaN"] {
            assert_eq!(
                parse_camera(bad),
                Err(ArgError::Camera(bad.to_string())),
                "{bad}"
            );
        }
        assert_eq!(
            parse_camera("0,1").expect_err("refused").to_string(),
            "'0,1' is not D,H or D,H,TX,TY,TZ (numbers, D > 0)"
        );
    }
}
