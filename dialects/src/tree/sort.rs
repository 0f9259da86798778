//! The `sort` builtin's exact semantics: Batcher's odd-even merge sort network over the array,
//! each comparator `(i, j)` (`i < j`) swapping elements `i` and `j` when `a[j] < a[i]`, where
//! `<` compares tuples component by component (the first that differs decides, by `<` on
//! numbers). For keys without NaN that is ascending order; with NaN it is still one fixed
//! sequence of compare-exchanges, so the interpreter and every backend agree bit for bit.

/// The comparators of Batcher's odd-even merge sort for `n` elements, in order (any `n`; 19
/// for 8 elements, 63 for 16).
pub fn network(n: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut p = 1;
    while p < n {
        let mut k = p;
        while k >= 1 {
            let mut j = k % p;
            while j + k < n {
                for i in 0..k.min(n - j - k) {
                    if (i + j) / (2 * p) == (i + j + k) / (2 * p) {
                        out.push((i + j, i + j + k));
                    }
                }
                j += 2 * k;
            }
            k /= 2;
        }
        p *= 2;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::network;

    /// The 0-1 principle: a comparator network sorts every input iff it sorts every sequence
    /// of zeros and ones.
    #[test]
    fn networks_sort_every_zero_one_sequence() {
        for n in 1..=12usize {
            let net = network(n);
            for bits in 0u32..(1 << n) {
                let mut a: Vec<u32> = (0..n).map(|i| (bits >> i) & 1).collect();
                for &(i, j) in &net {
                    assert!(i < j && j < n);
                    if a[j] < a[i] {
                        a.swap(i, j);
                    }
                }
                assert!(a.windows(2).all(|w| w[0] <= w[1]), "n = {n}, bits {bits:b}");
            }
        }
        assert_eq!(network(8).len(), 19);
    }
}
