//! The priority queue of candidate pairs.

/// A 4-ary min-heap of (candidate key, leaf): half the levels of a binary heap, and a
/// node's four children lie side by side. Pops in the order of the pairs, so ties between
/// equal keys go to the lower leaf.
pub(super) struct Queue {
    items: Vec<(u64, u32)>,
}

impl Queue {
    pub(super) fn with_capacity(capacity: usize) -> Queue {
        Queue {
            items: Vec::with_capacity(capacity),
        }
    }

    pub(super) fn push(&mut self, item: (u64, u32)) {
        let mut i = self.items.len();
        self.items.push(item);
        while i > 0 {
            let parent = (i - 1) / 4;
            if self.items[parent] <= item {
                break;
            }
            self.items[i] = self.items[parent];
            i = parent;
        }
        self.items[i] = item;
    }

    /// The least item, left in the queue.
    pub(super) fn peek(&self) -> Option<&(u64, u32)> {
        self.items.first()
    }

    pub(super) fn pop(&mut self) -> Option<(u64, u32)> {
        let last = self.items.pop()?;
        let Some(&top) = self.items.first() else {
            return Some(last);
        };
        self.sift_down(last);
        Some(top)
    }

    /// Replaces the least item with `item` (a pop then a push, in one sift-down).
    pub(super) fn replace_top(&mut self, item: (u64, u32)) {
        if self.items.is_empty() {
            self.items.push(item);
        } else {
            self.sift_down(item);
        }
    }

    /// Puts `item` in the root's place and moves it down to where it belongs.
    fn sift_down(&mut self, item: (u64, u32)) {
        let n = self.items.len();
        let mut i = 0;
        loop {
            let first = 4 * i + 1;
            if first >= n {
                break;
            }
            let end = (first + 4).min(n);
            let mut child = first;
            for c in first + 1..end {
                if self.items[c] < self.items[child] {
                    child = c;
                }
            }
            if self.items[child] >= item {
                break;
            }
            self.items[i] = self.items[child];
            i = child;
        }
        self.items[i] = item;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_queue_pops_in_increasing_order() {
        let mut queue = Queue::with_capacity(4);
        let mut items: Vec<(u64, u32)> = (0..500u32)
            .map(|i| (u64::from(i.wrapping_mul(2_654_435_761) % 97), i % 13))
            .collect();
        for &item in &items {
            queue.push(item);
        }
        items.sort_unstable();
        let popped: Vec<(u64, u32)> = std::iter::from_fn(|| queue.pop()).collect();
        assert_eq!(popped, items);
    }

    #[test]
    fn replacing_the_top_is_a_pop_then_a_push() {
        let mut a = Queue::with_capacity(4);
        let mut b = Queue::with_capacity(4);
        for i in 0..300u32 {
            let item = (u64::from(i.wrapping_mul(2_654_435_761) % 1000), i);
            a.push(item);
            b.push(item);
        }
        for i in 0..200u32 {
            let item = (u64::from(i.wrapping_mul(40_503) % 1500), 1000 + i);
            assert_eq!(a.pop(), b.peek().copied());
            a.push(item);
            b.replace_top(item);
        }
        let rest_a: Vec<_> = std::iter::from_fn(|| a.pop()).collect();
        let rest_b: Vec<_> = std::iter::from_fn(|| b.pop()).collect();
        assert_eq!(rest_a, rest_b);
        assert_eq!(rest_a.len(), 300);
    }
}
