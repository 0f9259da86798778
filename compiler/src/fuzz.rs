//! Input mutation for robustness testing of the front end.
//!
//! The compiler must not panic on any input. [`Mutator`] produces random and mutated sources
//! from seed texts (the library files): byte flips, deletions, duplications and splices of
//! ranges, insertions of Scion tokens at random places, and whole token soups. The suite runs a
//! short campaign (`compiler/tests/frontend_robustness.rs`); `examples/fuzz_frontend.rs` runs
//! long ones (see `docs/testing.md` for the recorded result).
//!
//! The generator is a deterministic xorshift so that every failure is reproducible from its
//! seed and iteration number.

/// Tokens that are inserted into mutated inputs, chosen to reach every parser and checker path.
pub const DICTIONARY: &[&str] = &[
    "type",
    "func",
    "layout",
    "build",
    "group",
    "indirect",
    "split",
    "by",
    "from",
    "let",
    "mut",
    "match",
    "if",
    "elif",
    "else",
    "foreach",
    "in",
    "return",
    "as",
    "to",
    "this",
    "parent",
    "true",
    "false",
    "inf",
    "root",
    "order",
    "pre",
    "post",
    "size",
    "align",
    "set",
    "option",
    "append",
    "(",
    ")",
    "{",
    "}",
    "[",
    "]",
    ";",
    ":",
    ",",
    ".",
    "->",
    "---",
    "|",
    "||",
    "&&",
    "=",
    "==",
    "!=",
    "<",
    "<=",
    ">",
    ">=",
    "<<",
    ">>",
    "+",
    "-",
    "*",
    "/",
    "%",
    "!",
    "~",
    "^",
    "&",
    "_",
    "0",
    "1",
    "255",
    "65535",
    "4294967295",
    "18446744073709551616",
    "0x1F",
    "0b101",
    "1.0",
    "1e-3",
    "1e40",
    "-0.0",
    "f32",
    "f32x3",
    "u16",
    "u32",
    "u64",
    "i32",
    "ptr",
    "bool",
    "AABB",
    "Ray",
    "Triangle",
    "BVH",
    "Interior",
    "Leaf",
    "bounds",
    "left",
    "right",
    "nprims",
    "data",
    "I",
    "N",
    "P",
    "x",
    "T[8]",
    "nodes[I]",
    "I[0:1]",
    "//",
    "\n",
    " ",
    "\"",
    "\u{e9}",
];

/// A small deterministic random number generator (xorshift64*).
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed (0 is replaced by a fixed odd constant).
    pub fn new(seed: u64) -> Rng {
        Rng(if seed == 0 {
            0x9E37_79B9_7F4A_7C15
        } else {
            seed
        })
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// A number in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

/// Produces mutated inputs from seed texts.
#[derive(Clone, Debug)]
pub struct Mutator {
    seeds: Vec<String>,
    rng: Rng,
}

impl Mutator {
    /// A mutator over `seeds` (must not be empty) with a fixed random seed.
    pub fn new(seeds: Vec<String>, seed: u64) -> Mutator {
        assert!(
            !seeds.is_empty(),
            "the mutator needs at least one seed text"
        );
        Mutator {
            seeds,
            rng: Rng::new(seed),
        }
    }

    /// The next input: usually a seed with 1-8 mutations, sometimes a token soup.
    pub fn next_input(&mut self) -> String {
        if self.rng.below(16) == 0 {
            return self.token_soup();
        }
        let mut text = self.seeds[self.rng.below(self.seeds.len())]
            .clone()
            .into_bytes();
        let rounds = 1 + self.rng.below(8);
        for _ in 0..rounds {
            self.mutate(&mut text);
        }
        String::from_utf8_lossy(&text).into_owned()
    }

    fn token_soup(&mut self) -> String {
        let n = self.rng.below(200);
        let mut s = String::new();
        for _ in 0..n {
            s.push_str(DICTIONARY[self.rng.below(DICTIONARY.len())]);
            if self.rng.below(3) != 0 {
                s.push(' ');
            }
        }
        s
    }

    fn range(&mut self, len: usize) -> (usize, usize) {
        if len == 0 {
            return (0, 0);
        }
        let start = self.rng.below(len);
        let max = (len - start).min(64);
        (start, start + self.rng.below(max + 1))
    }

    fn mutate(&mut self, text: &mut Vec<u8>) {
        let len = text.len();
        match self.rng.below(7) {
            0 if len > 0 => {
                let i = self.rng.below(len);
                text[i] ^= 1 << self.rng.below(8);
            }
            1 => {
                let (a, b) = self.range(len);
                text.drain(a..b);
            }
            2 => {
                let (a, b) = self.range(len);
                let piece = text[a..b].to_vec();
                let at = self.rng.below(len + 1);
                text.splice(at..at, piece);
            }
            3 => {
                let donor = self.seeds[self.rng.below(self.seeds.len())]
                    .as_bytes()
                    .to_vec();
                let (a, b) = self.range(donor.len());
                let at = self.rng.below(len + 1);
                text.splice(at..at, donor[a..b].iter().copied());
            }
            4 | 5 => {
                let tok = DICTIONARY[self.rng.below(DICTIONARY.len())].as_bytes();
                let at = self.rng.below(len + 1);
                text.splice(at..at, tok.iter().copied());
            }
            _ => {
                // Replace one whole line by a random dictionary token sequence.
                let lines: Vec<usize> = text
                    .iter()
                    .enumerate()
                    .filter(|(_, c)| **c == b'\n')
                    .map(|(i, _)| i)
                    .collect();
                if lines.len() > 1 {
                    let k = self.rng.below(lines.len() - 1);
                    let (a, b) = (lines[k] + 1, lines[k + 1]);
                    let mut repl = Vec::new();
                    for _ in 0..self.rng.below(6) {
                        repl.extend_from_slice(
                            DICTIONARY[self.rng.below(DICTIONARY.len())].as_bytes(),
                        );
                        repl.push(b' ');
                    }
                    text.splice(a..b, repl);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mutations_are_deterministic_and_change_the_input() {
        let seeds = vec!["type A(x: f32);\nfunc f(a: A) -> f32 = a.x\n".to_string()];
        let mut m1 = Mutator::new(seeds.clone(), 7);
        let mut m2 = Mutator::new(seeds.clone(), 7);
        let a: Vec<String> = (0..50).map(|_| m1.next_input()).collect();
        let b: Vec<String> = (0..50).map(|_| m2.next_input()).collect();
        assert_eq!(a, b);
        assert!(a.iter().filter(|s| **s != seeds[0]).count() > 40);
    }
}

/// Seed texts for the front end: the prelude alone and with each library file appended, so
/// that mutations reach types, functions, layouts and builds.
pub fn library_seeds(library: &std::path::Path) -> std::io::Result<Vec<String>> {
    let prelude = std::fs::read_to_string(library.join("prelude.scion"))?;
    let mut seeds = vec![prelude.clone(), CONSTRUCTS_SEED.to_string()];
    for rel in [
        "algorithms/closest_hit.scion",
        "algorithms/closest_point.scion",
        "layouts/pbrt.scion",
        "layouts/ptr.scion",
    ] {
        let text = std::fs::read_to_string(library.join(rel))?;
        seeds.push(format!("{prelude}\n{text}"));
        seeds.push(text);
    }
    for text in LAYOUT_SEEDS {
        seeds.push(format!("{prelude}\n{text}"));
    }
    Ok(seeds)
}

/// Layouts with constructs the library's layouts do not use yet: arrays of children
/// (`BVH4[4]`, `BVH8[8]`, `build children` into an array, `ch[k].bounds`), `sort`, array
/// literals, `foreach c, k in ch`, user functions in layout expressions, and a tree type the
/// a DOP-14 tree (the split layout of Fig. 12 and its closest hit), a best-first function
/// (`order by`), the shared slab (a reference of several components, a build reading its
/// children's boxes, tree-carried `parent.` components), and the hair BVH (three variants,
/// oriented child boxes, `f64` arithmetic, 64-bit tagged references).
pub const LAYOUT_SEEDS: [&str; 9] = [
    include_str!("../../lit-tests/Inputs/wide4_layout.scion"),
    concat!(
        include_str!("../../library/algorithms/closest_hit8.scion"),
        include_str!("../../library/layouts/bvh8_q8_ci.scion")
    ),
    concat!(
        include_str!("../../library/algorithms/closest_hit8.scion"),
        include_str!("../../library/layouts/bvh8.scion")
    ),
    include_str!("../../lit-tests/Inputs/user_functions_layout.scion"),
    concat!(
        include_str!("../../library/algorithms/closest_hit_dop14.scion"),
        include_str!("../../library/layouts/dop14_split.scion")
    ),
    include_str!("../../lit-tests/recursion-to-stack/deferred.scion"),
    include_str!("../../lit-tests/recursion-to-stack/best-first.scion"),
    include_str!("../../lit-tests/Inputs/shared_slab.scion"),
    concat!(
        include_str!("../../library/algorithms/closest_hit_hair.scion"),
        include_str!("../../library/layouts/hair_bvh.scion")
    ),
];

/// A seed with the traversal language's constructs that the library does not use yet
/// (`let mut`, `if` expressions, the lane and bit builtins), so that mutation reaches them.
pub const CONSTRUCTS_SEED: &str = r#"
func keep(best: mut (f32, u32), t: f32, id: u32) = {
  if t < best[0] { best = (t, id); }
}
func constructs(v: f32x3, n: u32) -> (f32, u32) = {
  let mut best = (inf, 0xFFFFFFFF);
  keep(best, hmin(v), popcount(n));
  let mut k: u32 = ctz(n | 1);
  k = k + clz(n);
  let s: f32 = if isnan(v.x) { 0.0 } elif v.y < v.z { hsum(v) } else { rsqrt(trunc(v.z)) };
  return (best[0] + s, if k > 3 { k } else { best[1] });
}
"#;

/// The outcome of one campaign.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Campaign {
    /// Inputs compiled.
    pub inputs: u64,
    /// Inputs the compiler accepted.
    pub accepted: u64,
    /// Inputs rejected with diagnostics.
    pub rejected: u64,
    /// Inputs that produced an internal compiler error (a bug, but not a crash).
    pub internal_errors: u64,
}

/// Compiles one source text through the whole front end (parse, sema, well-formedness,
/// irgen, `const-fold` and `dce`) with no prelude, and classifies the outcome.
pub fn compile_once(text: &str, campaign: &mut Campaign) -> Option<String> {
    use crate::driver::cli::Emit;
    use crate::frontend::{compile, Frontend, PassOptions};
    let mut sources = scion_ir::diag::SourceMap::new();
    let file = sources.add("fuzz.scion", text.to_string());
    let fe = Frontend {
        sources: &sources,
        prelude: &[],
        inputs: &[file],
    };
    let pipeline = vec!["const-fold".to_string(), "dce".to_string()];
    let r = compile(&fe, Emit::Tree, &pipeline, &PassOptions::default());
    campaign.inputs += 1;
    // Rendering is part of the contract: spans must stay inside their files.
    let _ = r.diagnostics.render(&sources);
    if let Some(ice) = r.internal_error {
        campaign.internal_errors += 1;
        return Some(ice.to_string());
    }
    if r.diagnostics.has_errors() {
        campaign.rejected += 1;
    } else {
        campaign.accepted += 1;
    }
    None
}
