//! A leaf budget for a whole forest (seed 003 §2.6 "Diseño de una aplicación de tiempo
//! real", figure 2.8 and algorithm 4 "Escalado"): each visible instance gets a tentative
//! number of leaves from its distance to the camera, then the numbers are rescaled
//! proportionally so that their sum meets the budget T.

use std::cmp::Reverse;

/// Why a budget cannot be computed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BudgetError {
    /// A distance, `near` or `far` is NaN, infinite or negative.
    #[error("{option} must be a finite number >= 0, got {value}")]
    Distance {
        /// `near`, `far` or `distances[i]` (1-based, as Lua counts).
        option: String,
        /// The value.
        value: f32,
    },
    /// `near` is beyond `far`.
    #[error("near must be at most far, got near = {near} and far = {far}")]
    NearBeyondFar {
        /// The near distance.
        near: f32,
        /// The far distance.
        far: f32,
    },
    /// The coarsest level has more leaves than the finest.
    #[error("roots must be between 1 and leaves, got roots = {roots} and leaves = {leaves}")]
    Roots {
        /// |R|.
        roots: u32,
        /// |O|.
        leaves: u32,
    },
}

/// The budget's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Budget {
    /// Under this distance an instance is drawn with all its leaves (the thesis' dmin).
    pub near: f32,
    /// Beyond this distance an instance is not drawn (the thesis' dmax).
    pub far: f32,
    /// The most leaves drawn in total (T).
    pub total: u64,
}

impl Budget {
    /// Checks that `near` and `far` are finite, non-negative and ordered.
    pub fn check(&self) -> Result<(), BudgetError> {
        for (option, value) in [("near", self.near), ("far", self.far)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(BudgetError::Distance {
                    option: option.into(),
                    value,
                });
            }
        }
        if self.near > self.far {
            return Err(BudgetError::NearBeyondFar {
                near: self.near,
                far: self.far,
            });
        }
        Ok(())
    }

    /// The tentative leaf count of an instance at `distance` (figure 2.8, nl): all `leaves`
    /// up to `near`, none beyond `far`, and between them a quadratic fall-off from `leaves`
    /// at `near` to `roots` at `far`: `roots + (leaves - roots) * ((far - d) / (far -
    /// near))^2`, rounded. A drawn instance never gets fewer than `roots`, its coarsest level.
    #[must_use]
    pub fn tentative(&self, distance: f32, leaves: u32, roots: u32) -> u32 {
        if distance <= self.near {
            leaves
        } else if distance > self.far {
            0
        } else {
            let t = (self.far - distance) / (self.far - self.near);
            let extra = (leaves - roots) as f32 * (t * t);
            roots + (extra.round() as u32).min(leaves - roots)
        }
    }
}

/// Assigns each instance the number of its `leaves` to draw, from its distance to the
/// camera, so that the total is at most `budget.total` (seed 003, algorithm 4 "Escalado").
///
/// The tentative counts ([`Budget::tentative`]) add up to D over the n drawn instances. If
/// `D > T`, each drawn instance loses its share `(d - |R|) / (D - n|R|) * (D - T)` of the
/// surplus, down to `|R|`; if `D < T`, each gains `(|O| - d) / (n|O| - D) * (T - D)`, up to
/// `|O|`. The thesis rounds every share up and walks the instances in input order until the
/// budget is met, so the last ones absorb the rounding. Here every share is rounded down and
/// the remainder (fewer leaves than instances) goes one leaf each to the farthest instances
/// that can still lose one, or the nearest that can still gain one: the budget is met exactly,
/// and since the shares grow with `d`, a nearer instance never gets fewer leaves than a
/// farther one. Where the thesis stops with an error because even `n|R|` exceeds T, the
/// farthest instances are left out (0 leaves) until the rest fit, as its text advises.
///
/// The level of an instance drawing `k > 0` leaves is `k - |R|` in the LOD table; 0 means
/// not drawn. Runs in linear time: a few passes over the instances, and a selection (not a
/// sort) wherever the farthest or nearest few are needed.
pub fn assign(
    distances: &[f32],
    leaves: u32,
    roots: u32,
    budget: &Budget,
) -> Result<Vec<u32>, BudgetError> {
    budget.check()?;
    if leaves > 0 && !(1..=leaves).contains(&roots) {
        return Err(BudgetError::Roots { roots, leaves });
    }
    for (i, &d) in distances.iter().enumerate() {
        if !(d.is_finite() && d >= 0.0) {
            return Err(BudgetError::Distance {
                option: format!("distances[{}]", i + 1),
                value: d,
            });
        }
    }
    let mut counts: Vec<u32> = distances
        .iter()
        .map(|&d| budget.tentative(d, leaves, roots))
        .collect();
    if leaves == 0 {
        return Ok(counts);
    }
    // Instances are ordered by distance, ties by index: non-negative finite floats order
    // like their bits.
    let key = |i: usize| (u64::from(distances[i].to_bits()) << 32) | i as u64;
    let (o, r, t) = (u64::from(leaves), u64::from(roots), budget.total);
    let mut drawn = counts.iter().filter(|&&c| c > 0).count() as u64;
    // Too many instances even at their coarsest: leave out the farthest.
    if drawn * r > t {
        let keep = (t / r) as usize;
        let mut keys: Vec<u64> = (0..counts.len())
            .filter(|&i| counts[i] > 0)
            .map(key)
            .collect();
        // keep < drawn, so the key at `keep` is the nearest left out.
        let (_, &mut first_out, _) = keys.select_nth_unstable(keep);
        for (i, c) in counts.iter_mut().enumerate() {
            if *c > 0 && key(i) >= first_out {
                *c = 0;
            }
        }
        drawn = keep as u64;
    }
    let sum: u64 = counts.iter().map(|&c| u64::from(c)).sum();
    let (d_min, d_max) = (drawn * r, drawn * o);
    if t < sum && sum > d_min {
        // Reduce: every drawn instance loses its share, rounded down...
        let (num, den) = (u128::from(sum - t), u128::from(sum - d_min));
        let mut left = sum - t;
        for c in counts.iter_mut().filter(|c| **c > 0) {
            let cut = (u128::from(u64::from(*c) - r) * num / den) as u64;
            *c -= cut as u32;
            left -= cut;
        }
        // ...and the farthest that can lose one more lose the remainder.
        spread(&mut counts, left, |c| c > roots, |i| Reverse(key(i)), -1);
    } else if t > sum && sum < d_max {
        // At most up to the full trees.
        let gain = t.min(d_max) - sum;
        let (num, den) = (u128::from(gain), u128::from(d_max - sum));
        let mut left = gain;
        for c in counts.iter_mut().filter(|c| **c > 0) {
            let add = (u128::from(o - u64::from(*c)) * num / den) as u64;
            *c += add as u32;
            left -= add;
        }
        spread(&mut counts, left, |c| c > 0 && c < leaves, key, 1);
    }
    Ok(counts)
}

/// Adds `step` (±1) to the count of the `left` first instances by `order` among those whose
/// count is `eligible`, found by a selection.
fn spread<K: Ord + Copy>(
    counts: &mut [u32],
    left: u64,
    eligible: impl Fn(u32) -> bool,
    order: impl Fn(usize) -> K,
    step: i32,
) {
    if left == 0 {
        return;
    }
    let mut keys: Vec<K> = (0..counts.len())
        .filter(|&i| eligible(counts[i]))
        .map(&order)
        .collect();
    let n = (left as usize).min(keys.len());
    if n == 0 {
        return;
    }
    let (_, &mut last, _) = keys.select_nth_unstable(n - 1);
    for (i, c) in counts.iter_mut().enumerate() {
        if eligible(*c) && order(i) <= last {
            *c = c.saturating_add_signed(step);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn budget(total: u64) -> Budget {
        Budget {
            near: 10.0,
            far: 110.0,
            total,
        }
    }

    #[test]
    fn tentative_counts_fall_off_quadratically() {
        let b = budget(0);
        assert_eq!(b.tentative(5.0, 1000, 10), 1000);
        assert_eq!(b.tentative(10.0, 1000, 10), 1000);
        assert_eq!(b.tentative(60.0, 1000, 10), 10 + 248); // 990 / 4 = 247.5
        assert_eq!(b.tentative(110.0, 1000, 10), 10);
        assert_eq!(b.tentative(110.5, 1000, 10), 0);
    }

    #[test]
    fn a_tight_budget_is_met_exactly_and_keeps_the_order() {
        let distances: Vec<f32> = (0..50).map(|i| ((i * 37) % 50) as f32 * 2.5).collect();
        let counts = assign(&distances, 1000, 10, &budget(5000)).expect("budget");
        let total: u64 = counts.iter().map(|&c| u64::from(c)).sum();
        assert_eq!(total, 5000);
        for i in 0..50 {
            for j in 0..50 {
                if distances[i] < distances[j] {
                    assert!(counts[i] >= counts[j], "{i} {j} {counts:?}");
                }
            }
            assert!(counts[i] == 0 || counts[i] >= 10);
        }
    }

    #[test]
    fn a_generous_budget_raises_counts_up_to_the_full_tree() {
        let distances = [50.0, 20.0, 100.0, 200.0];
        let tentative: Vec<u32> = distances
            .iter()
            .map(|&d| budget(0).tentative(d, 100, 4))
            .collect();
        let counts = assign(&distances, 100, 4, &budget(250)).expect("budget");
        assert_eq!(counts.iter().sum::<u32>(), 250);
        assert_eq!(counts[3], 0, "beyond far stays hidden");
        for i in 0..3 {
            assert!(counts[i] >= tentative[i] && counts[i] <= 100);
        }
        assert!(counts[1] >= counts[0] && counts[0] >= counts[2]);
        let all = assign(&distances, 100, 4, &budget(10_000)).expect("budget");
        assert_eq!(all, vec![100, 100, 100, 0]);
    }

    #[test]
    fn too_many_instances_leave_out_the_farthest() {
        let distances = [1.0, 2.0, 3.0, 4.0];
        let counts = assign(&distances, 100, 10, &budget(25)).expect("budget");
        assert_eq!(counts, vec![13, 12, 0, 0]);
    }

    #[test]
    fn bad_distances_are_errors() {
        let nan = assign(&[1.0, f32::NAN], 10, 1, &budget(5)).expect_err("nan");
        assert_eq!(
            nan.to_string(),
            "distances[2] must be a finite number >= 0, got NaN"
        );
        let neg = Budget {
            near: -1.0,
            ..budget(5)
        };
        assert!(matches!(
            assign(&[], 10, 1, &neg),
            Err(BudgetError::Distance { .. })
        ));
        let swapped = Budget {
            near: 20.0,
            far: 10.0,
            total: 5,
        };
        assert_eq!(
            assign(&[], 10, 1, &swapped).expect_err("order").to_string(),
            "near must be at most far, got near = 20 and far = 10"
        );
        assert!(matches!(
            assign(&[1.0], 10, 11, &budget(5)),
            Err(BudgetError::Roots { .. })
        ));
    }
}
