//! Attributes: the compile-time data of an operation (constants, predicates, field names and
//! indices, bit ranges, callee symbols, arm lists), kept in a small dictionary sorted by name.
//!
//! Attributes compare by value and never hold spans, so two ops with equal kinds, operands and
//! attributes are equal (what CSE needs). Floats are stored as the bits of an `f64` (an `f32`
//! or `f16` constant is stored widened, which is exact), so equality is bit equality: `-0.0` and
//! `0.0` differ, and a NaN equals itself. Their text form round-trips exactly: finite values
//! print in Rust's shortest round-trip decimal form, infinities as `inf`/`-inf`, the canonical
//! quiet NaN as `nan` and any other NaN as `nan(0x<f64 bits>)`. On ops computing in `f32`, an
//! exact `f32` may print as the typed literal `1.0000004 : f32` (its shortest `f32` spelling),
//! which the parser reads as an `f32` and widens, so the bits still round-trip.

use crate::entity::TypeId;
use crate::types::TypeTable;
use smallvec::SmallVec;
use std::fmt::Write;

/// One attribute value.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum Attr {
    /// A flag whose presence is the information (`unit`).
    Unit,
    /// `true` / `false`.
    Bool(bool),
    /// An integer (wide enough for every `i64` and `u64`).
    Int(i128),
    /// A float, as the bits of an `f64`.
    Float(u64),
    /// A string, `"..."`.
    Str(String),
    /// A symbol reference, `@name`.
    Sym(String),
    /// A type.
    Type(TypeId),
    /// A list, `[a, b]`.
    List(Vec<Attr>),
}

impl Attr {
    /// A float attribute holding `v` exactly.
    pub fn float(v: f64) -> Attr {
        Attr::Float(v.to_bits())
    }

    /// A string attribute.
    pub fn str(s: impl Into<String>) -> Attr {
        Attr::Str(s.into())
    }

    /// The integer, if this is one.
    pub fn as_int(&self) -> Option<i128> {
        match self {
            Attr::Int(v) => Some(*v),
            _ => None,
        }
    }

    /// The float, if this is one.
    pub fn as_float(&self) -> Option<f64> {
        match self {
            Attr::Float(b) => Some(f64::from_bits(*b)),
            _ => None,
        }
    }

    /// The string, if this is one.
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Attr::Str(s) => Some(s),
            _ => None,
        }
    }

    /// The symbol name, if this is one.
    pub fn as_sym(&self) -> Option<&str> {
        match self {
            Attr::Sym(s) => Some(s),
            _ => None,
        }
    }

    /// The list, if this is one.
    pub fn as_list(&self) -> Option<&[Attr]> {
        match self {
            Attr::List(l) => Some(l),
            _ => None,
        }
    }

    /// Writes the text form of the attribute.
    pub fn print(&self, types: &TypeTable, out: &mut String) {
        self.print_with_hint(types, out, false)
    }

    /// Writes the text form; with `f32_hint` (the op computes in `f32`), a float that is an
    /// exact `f32` whose shortest `f32` spelling is shorter than its `f64` one prints as the
    /// typed literal `1.0000004 : f32`, which the parser reads back as that `f32` exactly.
    pub fn print_with_hint(&self, types: &TypeTable, out: &mut String, f32_hint: bool) {
        match self {
            Attr::Unit => out.push_str("unit"),
            Attr::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
            Attr::Int(v) => {
                let _ = write!(out, "{v}");
            }
            Attr::Float(bits) => match f32_spelling(*bits).filter(|_| f32_hint) {
                Some(short) => {
                    out.push_str(&short);
                    out.push_str(" : f32");
                }
                None => out.push_str(&format_float(*bits)),
            },
            Attr::Str(s) => out.push_str(&quote(s)),
            Attr::Sym(s) => {
                out.push('@');
                out.push_str(&symbol_text(s));
            }
            Attr::Type(t) => {
                let _ = write!(out, "{}", types.display(*t));
            }
            Attr::List(items) => {
                out.push('[');
                for (i, a) in items.iter().enumerate() {
                    if i > 0 {
                        out.push_str(", ");
                    }
                    a.print_with_hint(types, out, f32_hint);
                }
                out.push(']');
            }
        }
    }
}

/// The bits of the canonical quiet NaN printed as plain `nan`.
pub const CANONICAL_NAN_BITS: u64 = 0x7ff8_0000_0000_0000;

/// The exact text form of an `f64` given by its bits (see the module docs).
pub fn format_float(bits: u64) -> String {
    let v = f64::from_bits(bits);
    if v.is_nan() {
        if bits == CANONICAL_NAN_BITS {
            "nan".to_string()
        } else {
            format!("nan(0x{bits:016x})")
        }
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.to_string()
    } else {
        // `{:?}` is the shortest decimal that parses back to the same bits and always has a `.`
        // or an exponent, so the parser can tell it from an integer.
        let s = format!("{v:?}");
        if s.contains('.') || s.contains('e') || s.contains('E') {
            s
        } else {
            format!("{s}.0")
        }
    }
}

/// The shortest `f32` spelling of the `f64` given by `bits` when the value is a finite `f32`
/// and that spelling is shorter than the shortest `f64` one (`1.0000004` for the widened
/// `1.0000004f32`, printed as `1.0000004768371582` otherwise).
pub fn f32_spelling(bits: u64) -> Option<String> {
    let v = f64::from_bits(bits);
    let narrow = v as f32;
    if !v.is_finite() || narrow as f64 != v {
        return None;
    }
    let short = format!("{narrow:?}");
    (short.len() < format_float(bits).len()).then_some(short)
}

/// `s` as a double-quoted string literal with `\"`, `\\`, `\n`, `\t` and `\u{..}` escapes.
pub fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// True when `s` can be written without quotes after `@`: `[A-Za-z_][A-Za-z0-9_.$]*`.
pub fn is_bare_symbol(s: &str) -> bool {
    let mut chars = s.chars();
    match chars.next() {
        Some(c) if c.is_ascii_alphabetic() || c == '_' => {}
        _ => return false,
    }
    chars.all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.' || c == '$')
}

/// A symbol name as written after `@`: bare when possible, quoted otherwise (overloaded
/// functions get mangled names such as `intersects(Ray,AABB)`).
pub fn symbol_text(s: &str) -> String {
    if is_bare_symbol(s) {
        s.to_string()
    } else {
        quote(s)
    }
}

/// An operation's attribute dictionary, sorted by name, each name at most once.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash)]
pub struct Attrs {
    entries: SmallVec<[(String, Attr); 2]>,
}

impl Attrs {
    /// An empty dictionary.
    pub fn new() -> Attrs {
        Attrs::default()
    }

    /// Sets `name` to `value`, replacing an earlier value.
    pub fn set(&mut self, name: &str, value: Attr) {
        match self.entries.binary_search_by(|(n, _)| n.as_str().cmp(name)) {
            Ok(i) => self.entries[i].1 = value,
            Err(i) => self.entries.insert(i, (name.to_string(), value)),
        }
    }

    /// The value of `name`.
    pub fn get(&self, name: &str) -> Option<&Attr> {
        self.entries
            .binary_search_by(|(n, _)| n.as_str().cmp(name))
            .ok()
            .map(|i| &self.entries[i].1)
    }

    /// Removes `name`, returning its value.
    pub fn remove(&mut self, name: &str) -> Option<Attr> {
        match self.entries.binary_search_by(|(n, _)| n.as_str().cmp(name)) {
            Ok(i) => Some(self.entries.remove(i).1),
            Err(_) => None,
        }
    }

    /// The entries in name order.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &Attr)> {
        self.entries.iter().map(|(n, a)| (n.as_str(), a))
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_print_exactly() {
        for v in [
            0.0,
            -0.0,
            1.0,
            0.1,
            1e300,
            f64::MIN_POSITIVE,
            5e-324,
            0.1f32 as f64,
        ] {
            let s = format_float(v.to_bits());
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{s}");
        }
        assert_eq!(format_float(f64::INFINITY.to_bits()), "inf");
        assert_eq!(format_float(f64::NEG_INFINITY.to_bits()), "-inf");
        assert_eq!(format_float(CANONICAL_NAN_BITS), "nan");
        assert_eq!(
            format_float(0xfff8_0000_0000_0001),
            "nan(0xfff8000000000001)"
        );
        assert_eq!(format_float(1e21f64.to_bits()), "1e21");
    }

    #[test]
    fn dictionary_stays_sorted() {
        let mut a = Attrs::new();
        a.set("index", Attr::Int(1));
        a.set("name", Attr::str("x"));
        a.set("arms", Attr::List(vec![]));
        a.set("index", Attr::Int(2));
        let names: Vec<_> = a.iter().map(|(n, _)| n).collect();
        assert_eq!(names, ["arms", "index", "name"]);
        assert_eq!(a.get("index"), Some(&Attr::Int(2)));
        assert_eq!(
            symbol_text("intersects(Ray,AABB)"),
            "\"intersects(Ray,AABB)\""
        );
    }
}
