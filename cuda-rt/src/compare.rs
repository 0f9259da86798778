//! Comparing GPU hits with the CPU reference, bit for bit: the distance's bits and the
//! primitive id of every ray. Input: two hit lists; output: a [`Comparison`] whose `Display`
//! is the line `scion trace --device gpu` and `scion-gpu` print.

use scion_runtime::geom::Hit;
use std::fmt;

/// How two hit lists differ.
#[derive(Clone, Debug, PartialEq)]
pub struct Comparison {
    /// Rays compared.
    pub rays: usize,
    /// Rays whose hits differ.
    pub differing: usize,
    /// The first differing ray: index, GPU hit, reference hit.
    pub first: Option<(usize, Hit, Hit)>,
}

impl Comparison {
    /// Compares `gpu` with `reference` (same length expected; extra entries count as
    /// differing).
    pub fn of(gpu: &[Hit], reference: &[Hit]) -> Comparison {
        let same = |a: &Hit, b: &Hit| a.t.to_bits() == b.t.to_bits() && a.prim == b.prim;
        let mut differing = gpu.len().abs_diff(reference.len());
        let mut first = None;
        for (i, (g, r)) in gpu.iter().zip(reference).enumerate() {
            if !same(g, r) {
                differing += 1;
                first.get_or_insert((i, *g, *r));
            }
        }
        Comparison {
            rays: gpu.len().max(reference.len()),
            differing,
            first,
        }
    }

    /// True when every hit is identical.
    pub fn identical(&self) -> bool {
        self.differing == 0
    }
}

fn hit(h: &Hit) -> String {
    if h.is_hit() {
        format!("(t {:?}, prim {})", h.t, h.prim)
    } else {
        "miss".to_string()
    }
}

impl fmt::Display for Comparison {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.identical() {
            return write!(f, "identical to the reference on all {} rays", self.rays);
        }
        write!(
            f,
            "{} of {} hits differ from the reference",
            self.differing, self.rays
        )?;
        if let Some((i, g, r)) = &self.first {
            write!(f, "; first: ray {i}: gpu {}, reference {}", hit(g), hit(r))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compares_bits_and_ids() {
        let a = vec![Hit::from_best(1.0, 3), Hit::MISS, Hit::from_best(2.0, 4)];
        let c = Comparison::of(&a, &a);
        assert!(c.identical());
        assert_eq!(c.to_string(), "identical to the reference on all 3 rays");
        let mut b = a.clone();
        b[2] = Hit::from_best(f32::from_bits(2.0f32.to_bits() + 1), 4);
        b[1] = Hit::from_best(5.0, 1);
        let c = Comparison::of(&b, &a);
        assert_eq!(c.differing, 2);
        assert_eq!(
            c.to_string(),
            "2 of 3 hits differ from the reference; first: ray 1: gpu (t 5.0, prim 1), \
             reference miss"
        );
        let c = Comparison::of(&a[..2], &a);
        assert_eq!((c.rays, c.differing), (3, 1));
    }
}
