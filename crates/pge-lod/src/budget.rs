//! A leaf budget for a whole forest (seed 003 §2.6 "Diseño de una aplicación de tiempo
//! real", figure 2.8 and algorithm 4 "Escalado"): each visible instance gets a tentative
//! number of leaves from its distance to the camera, then the numbers are rescaled
//! proportionally so that their sum meets the budget T.

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
        // Computed whatever the distance, then chosen: no branch to mispredict when the
        // distances come in no order (a division by 0 when near = far is never chosen).
        let span = leaves.saturating_sub(roots);
        let t = (self.far - distance) / (self.far - self.near);
        let between = roots + round(span as f32 * (t * t)).min(span);
        let beyond = if distance > self.far { 0 } else { between };
        if distance <= self.near {
            leaves
        } else {
            beyond
        }
    }
}

/// `x.round() as u32` for `x >= 0` without a call to the C library's `roundf`: halves
/// round away from zero, and `as` saturates above `u32::MAX`.
fn round(x: f32) -> u32 {
    let whole = x as u32;
    // Exact: below 2^24 `whole` is exact as a float, above it `x` is a whole number.
    let fraction = x - whole as f32;
    whole.saturating_add(u32::from(fraction >= 0.5))
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
/// sort) wherever the farthest or nearest few are needed. A renderer calling it every frame
/// uses [`assign_into`], which reuses its buffers.
pub fn assign(
    distances: &[f32],
    leaves: u32,
    roots: u32,
    budget: &Budget,
) -> Result<Vec<u32>, BudgetError> {
    let mut counts = Vec::new();
    assign_into(distances, leaves, roots, budget, &mut counts)?;
    Ok(counts)
}

/// [`assign`] into `counts` (cleared first): nothing is allocated once it has grown to the
/// number of instances, and the few farthest or nearest instances are found by a radix
/// selection over the distances' bits (three counting passes) instead of sorting or
/// copying keys. On an error `counts` is left empty.
pub fn assign_into(
    distances: &[f32],
    leaves: u32,
    roots: u32,
    budget: &Budget,
    counts: &mut Vec<u32>,
) -> Result<(), BudgetError> {
    counts.clear();
    budget.check()?;
    if leaves > 0 && !(1..=leaves).contains(&roots) {
        return Err(BudgetError::Roots { roots, leaves });
    }
    // One pass: the tentative counts, their sum and how many are drawn.
    let (mut sum, mut drawn) = (0u64, 0u64);
    counts.reserve(distances.len());
    for (i, &d) in distances.iter().enumerate() {
        if !(d.is_finite() && d >= 0.0) {
            counts.clear();
            return Err(BudgetError::Distance {
                option: format!("distances[{}]", i + 1),
                value: d,
            });
        }
        let c = budget.tentative(d, leaves, roots);
        sum += u64::from(c);
        drawn += u64::from(c > 0);
        counts.push(c);
    }
    if leaves == 0 {
        return Ok(());
    }
    // Instances are ordered by distance, ties by index: non-negative finite floats order
    // like their bits.
    let key = |i: usize| (u64::from(distances[i].to_bits()) << 32) | i as u64;
    let (o, r, t) = (u64::from(leaves), u64::from(roots), budget.total);
    // Too many instances even at their coarsest: leave out the farthest.
    if drawn * r > t {
        let keep = (t / r) as usize;
        // keep < drawn: the key of the nearest left out.
        let first_out = nth_key(distances, counts, |c| c > 0, keep + 1, false);
        sum = 0;
        for (i, c) in counts.iter_mut().enumerate() {
            if *c > 0 && key(i) >= first_out {
                *c = 0;
            }
            sum += u64::from(*c);
        }
        drawn = keep as u64;
    }
    let (d_min, d_max) = (drawn * r, drawn * o);
    if t < sum && sum > d_min {
        // Reduce: every drawn instance loses its share, rounded down...
        let share = Share::new(sum - t, sum - d_min);
        let mut left = sum - t;
        for c in counts.iter_mut().filter(|c| **c > 0) {
            let cut = share.of(u64::from(*c) - r);
            *c -= cut as u32;
            left -= cut;
        }
        // ...and the farthest that can lose one more lose the remainder.
        spread(distances, counts, left, |c| c > roots, true);
    } else if t > sum && sum < d_max {
        // At most up to the full trees.
        let gain = t.min(d_max) - sum;
        let share = Share::new(gain, d_max - sum);
        let mut left = gain;
        for c in counts.iter_mut().filter(|c| **c > 0) {
            let add = share.of(o - u64::from(*c));
            *c += add as u32;
            left -= add;
        }
        spread(distances, counts, left, |c| c > 0 && c < leaves, false);
    }
    Ok(())
}

/// The exact share `floor(x * num / den)` of each `x` (with `num <= den`), computed with a
/// floating-point estimate and corrected with exact products: no integer division per
/// instance (a 128-bit division costs as much as the rest of the pass).
struct Share {
    num: u128,
    den: u128,
    ratio: f64,
}

impl Share {
    fn new(num: u64, den: u64) -> Share {
        Share {
            num: u128::from(num),
            den: u128::from(den),
            ratio: num as f64 / den as f64,
        }
    }

    fn of(&self, x: u64) -> u64 {
        // x <= 2^32, so the estimate is within 2^-20 of the exact quotient (at most x):
        // away from whole numbers its floor is exact, near them exact products decide.
        let estimate = x as f64 * self.ratio;
        let mut q = (estimate as u64).min(x);
        let fraction = estimate - q as f64;
        if fraction > 1e-4 && fraction < 1.0 - 1e-4 {
            return q;
        }
        let exact = u128::from(x) * self.num;
        while u128::from(q) * self.den > exact {
            q -= 1;
        }
        while (u128::from(q) + 1) * self.den <= exact {
            q += 1;
        }
        q
    }
}

/// Adds one leaf to (or, `farthest`, takes one from) each of the `left` nearest (farthest)
/// instances whose count is `eligible`, in the order of (distance, index) (reversed): the
/// radix selection finds the distance of the last one, then one pass walks the instances in
/// index order (reversed) and changes those before that distance and the first ones at it.
fn spread(
    distances: &[f32],
    counts: &mut [u32],
    left: u64,
    eligible: impl Fn(u32) -> bool + Copy,
    farthest: bool,
) {
    let Some((last, mut ties)) = radix(distances, counts, eligible, left, farthest) else {
        return;
    };
    let mut visit = |(&d, c): (&f32, &mut u32)| {
        if !eligible(*c) {
            return;
        }
        let bits = d.to_bits();
        let before = if farthest { bits > last } else { bits < last };
        if before || (bits == last && ties > 0) {
            ties -= usize::from(bits == last);
            *c = if farthest { *c - 1 } else { *c + 1 };
        }
    };
    if farthest {
        distances.iter().zip(counts).rev().for_each(&mut visit);
    } else {
        distances.iter().zip(counts).for_each(&mut visit);
    }
}

/// The key `(distance bits << 32) | index` of the `n`-th (from 1) instance whose count is
/// `eligible`, in increasing order of keys (decreasing when `farthest`). `n` is at least 1
/// and at most the number of eligible instances.
fn nth_key(
    distances: &[f32],
    counts: &[u32],
    eligible: impl Fn(u32) -> bool + Copy,
    n: usize,
    farthest: bool,
) -> u64 {
    let (bits, rank) = radix(distances, counts, eligible, n as u64, farthest).unwrap_or((0, 1));
    // The `rank`-th instance at exactly this distance, by index (decreasing when `farthest`).
    let mut at =
        (0..distances.len()).filter(|&i| eligible(counts[i]) && distances[i].to_bits() == bits);
    let i = if farthest {
        at.rev().nth(rank - 1)
    } else {
        at.nth(rank - 1)
    };
    (u64::from(bits) << 32) | i.unwrap_or(0) as u64
}

/// A radix selection of the `n`-th (from 1; fewer when fewer are eligible) instance whose
/// count is `eligible`, by increasing distance (decreasing when `farthest`): three counting
/// passes over the distance's bits, 11, 11 and 10 at a time. Its distance's bits, and how
/// many of the instances at exactly that distance are among the first `n`; `None` when
/// `n` is 0 or none is eligible.
fn radix(
    distances: &[f32],
    counts: &[u32],
    eligible: impl Fn(u32) -> bool,
    n: u64,
    farthest: bool,
) -> Option<(u32, usize)> {
    let (mut prefix, mut mask, mut rank) = (0u32, 0u32, 0usize);
    let mut histogram = [0u32; 1 << 11];
    for (shift, width) in [(21u32, 11u32), (10, 11), (0, 10)] {
        let digits = &mut histogram[..1 << width];
        digits.fill(0);
        let digit_mask = (1u32 << width) - 1;
        for (&d, &c) in distances.iter().zip(counts) {
            let bits = d.to_bits();
            if eligible(c) && bits & mask == prefix {
                digits[((bits >> shift) & digit_mask) as usize] += 1;
            }
        }
        if mask == 0 {
            // The first pass counted every eligible instance.
            let total: u64 = digits.iter().map(|&c| u64::from(c)).sum();
            rank = n.min(total) as usize;
            if rank == 0 {
                return None;
            }
        }
        let mut pick = |digit: usize, count: u32| {
            if rank <= count as usize {
                prefix |= (digit as u32) << shift;
                true
            } else {
                rank -= count as usize;
                false
            }
        };
        if farthest {
            let _ = digits.iter().enumerate().rev().any(|(d, &c)| pick(d, c));
        } else {
            let _ = digits.iter().enumerate().any(|(d, &c)| pick(d, c));
        }
        mask |= digit_mask << shift;
    }
    Some((prefix, rank))
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
    fn shares_are_the_exact_rounded_down_quotients() {
        let mut x = 1u64;
        for &(num, den) in &[
            (1, 3),
            (7, 7),
            (999_999, 1_000_000),
            (1 << 40, (1 << 41) + 3),
        ] {
            let share = Share::new(num, den);
            for _ in 0..2000 {
                x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                let v = x >> 32;
                let exact = u128::from(v) * u128::from(num) / u128::from(den);
                assert_eq!(u128::from(share.of(v)), exact, "{v} * {num} / {den}");
            }
        }
    }

    #[test]
    fn rounding_matches_the_standard_library() {
        let mut values = vec![0.0, 0.5, 1.5, 2.5, 0.499_999_97, 8_388_609.0, 1e10, 4.2e9];
        values.extend((0..5000).map(|i| i as f32 * 0.137 + 0.25));
        for x in values {
            assert_eq!(round(x), x.round() as u32, "{x}");
        }
    }

    #[test]
    fn the_radix_selection_finds_the_nth_key() {
        // Many equal distances, so that ties by index matter.
        let distances: Vec<f32> = (0..700u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) % 53) as f32 * 0.75)
            .collect();
        let counts: Vec<u32> = (0..700u32).map(|i| i % 3).collect();
        let eligible = |c: u32| c > 0;
        let mut keys: Vec<u64> = (0..700)
            .filter(|&i| eligible(counts[i]))
            .map(|i| (u64::from(distances[i].to_bits()) << 32) | i as u64)
            .collect();
        keys.sort_unstable();
        for n in [1, 2, 17, 100, keys.len()] {
            assert_eq!(
                nth_key(&distances, &counts, eligible, n, false),
                keys[n - 1]
            );
            let far = keys[keys.len() - n];
            assert_eq!(nth_key(&distances, &counts, eligible, n, true), far);
        }
    }

    #[test]
    fn reused_buffers_give_the_same_counts() {
        let distances: Vec<f32> = (0..300).map(|i| ((i * 37) % 300) as f32 * 0.4).collect();
        let mut counts = Vec::new();
        for total in [100, 5000, 40_000, 1_000_000] {
            let fresh = assign(&distances, 1000, 10, &budget(total)).expect("budget");
            assign_into(&distances, 1000, 10, &budget(total), &mut counts).expect("budget");
            assert_eq!(counts, fresh);
            let sum: u64 = counts.iter().map(|&c| u64::from(c)).sum();
            assert!(sum <= total);
        }
        let bad = assign_into(&[f32::NAN], 10, 1, &budget(5), &mut counts);
        assert!(bad.is_err() && counts.is_empty());
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
