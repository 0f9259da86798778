//! Unification of semantic types with inference variables (Hindley-Milner, monomorphic).
//!
//! Input: types built by the checker, some holding [`Ty::Var`]s. Output: variable bindings, so
//! that [`Checker::zonk`] gives each type its final form. A variable created for an integer
//! literal may only become an integer type, one for a float literal only a float type; after
//! inference the survivors default to `i32` and `f32` (paper §3: literals are typed by use).

use super::infer::Checker;
use super::types::{Prim, Ty, TyVar};

/// What an inference variable may become.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum VarKind {
    /// Anything.
    General,
    /// An integer type (the variable of an integer literal).
    Int,
    /// A float type (the variable of a float literal).
    Float,
}

/// One inference variable.
#[derive(Clone, Debug)]
pub(super) struct VarState {
    pub bound: Option<Ty>,
    pub kind: VarKind,
}

/// Why two types did not unify.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum UnifyError {
    /// Different types.
    Mismatch,
    /// A variable would contain itself.
    Occurs,
}

impl Checker<'_> {
    /// A fresh variable.
    pub(super) fn fresh(&mut self, kind: VarKind) -> Ty {
        self.vars.push(VarState { bound: None, kind });
        Ty::Var(TyVar(self.vars.len() as u32 - 1))
    }

    /// `t` with bound variables at its head followed.
    pub(super) fn shallow(&self, t: &Ty) -> Ty {
        let mut t = t.clone();
        while let Ty::Var(v) = t {
            match &self.vars[v.0 as usize].bound {
                Some(b) => t = b.clone(),
                None => return t,
            }
        }
        t
    }

    /// The kind of an unbound variable (after following bindings), if `t` is one.
    pub(super) fn var_kind(&self, t: &Ty) -> Option<VarKind> {
        match self.shallow(t) {
            Ty::Var(v) => Some(self.vars[v.0 as usize].kind),
            _ => None,
        }
    }

    /// `t` with every bound variable replaced, deeply.
    pub(super) fn zonk(&self, t: &Ty) -> Ty {
        match self.shallow(t) {
            Ty::Tuple(ts) => Ty::Tuple(ts.iter().map(|t| self.zonk(t)).collect()),
            Ty::Array(e, n) => Ty::Array(Box::new(self.zonk(&e)), n),
            Ty::Slice(e) => Ty::Slice(Box::new(self.zonk(&e))),
            Ty::Set(e) => Ty::Set(Box::new(self.zonk(&e))),
            Ty::Option(e) => Ty::Option(Box::new(self.zonk(&e))),
            t => t,
        }
    }

    /// The type as the user would write it; unsolved literal variables print as `{integer}`
    /// and `{float}`.
    pub(super) fn show(&self, t: &Ty) -> String {
        match self.shallow(t) {
            Ty::Var(v) => match self.vars[v.0 as usize].kind {
                VarKind::General => "_".to_string(),
                VarKind::Int => "{integer}".to_string(),
                VarKind::Float => "{float}".to_string(),
            },
            Ty::Tuple(ts) => {
                let parts: Vec<String> = ts.iter().map(|t| self.show(t)).collect();
                format!("({})", parts.join(", "))
            }
            Ty::Array(e, n) => format!("{}[{n}]", self.show(&e)),
            Ty::Slice(e) => format!("{}[..]", self.show(&e)),
            Ty::Set(e) => format!("set[{}]", self.show(&e)),
            Ty::Option(e) => format!("option[{}]", self.show(&e)),
            t => t.display(&self.adts).to_string(),
        }
    }

    fn occurs(&self, v: TyVar, t: &Ty) -> bool {
        match self.shallow(t) {
            Ty::Var(w) => v == w,
            Ty::Tuple(ts) => ts.iter().any(|t| self.occurs(v, t)),
            Ty::Array(e, _) | Ty::Slice(e) | Ty::Set(e) | Ty::Option(e) => self.occurs(v, &e),
            _ => false,
        }
    }

    fn kind_admits(kind: VarKind, t: &Ty) -> bool {
        match kind {
            VarKind::General => true,
            VarKind::Int => matches!(t, Ty::Prim(p) if p.is_int()) || matches!(t, Ty::Error),
            VarKind::Float => matches!(t, Ty::Prim(p) if p.is_float()) || matches!(t, Ty::Error),
        }
    }

    fn bind(&mut self, v: TyVar, t: Ty) -> Result<(), UnifyError> {
        if let Ty::Var(w) = t {
            if v == w {
                return Ok(());
            }
            let (kv, kw) = (self.vars[v.0 as usize].kind, self.vars[w.0 as usize].kind);
            let merged = match (kv, kw) {
                (VarKind::General, k) | (k, VarKind::General) => k,
                (a, b) if a == b => a,
                _ => return Err(UnifyError::Mismatch),
            };
            self.vars[w.0 as usize].kind = merged;
            self.vars[v.0 as usize].bound = Some(Ty::Var(w));
            return Ok(());
        }
        if !Self::kind_admits(self.vars[v.0 as usize].kind, &t) {
            return Err(UnifyError::Mismatch);
        }
        if self.occurs(v, &t) {
            return Err(UnifyError::Occurs);
        }
        self.vars[v.0 as usize].bound = Some(t);
        Ok(())
    }

    /// Makes `a` and `b` the same type.
    pub(super) fn unify(&mut self, a: &Ty, b: &Ty) -> Result<(), UnifyError> {
        let (a, b) = (self.shallow(a), self.shallow(b));
        match (a, b) {
            (Ty::Error, _) | (_, Ty::Error) => Ok(()),
            (Ty::Var(v), t) | (t, Ty::Var(v)) => self.bind(v, t),
            (Ty::Prim(p), Ty::Prim(q)) if p == q => Ok(()),
            (Ty::Vector(p, n), Ty::Vector(q, m)) if p == q && n == m => Ok(()),
            (Ty::Ptr, Ty::Ptr) => Ok(()),
            (Ty::Adt(x), Ty::Adt(y)) if x == y => Ok(()),
            (Ty::Tuple(xs), Ty::Tuple(ys)) if xs.len() == ys.len() => {
                for (x, y) in xs.iter().zip(ys.iter()) {
                    self.unify(x, y)?;
                }
                Ok(())
            }
            (Ty::Array(x, n), Ty::Array(y, m)) if n == m => self.unify(&x, &y),
            (Ty::Slice(x), Ty::Slice(y))
            | (Ty::Set(x), Ty::Set(y))
            | (Ty::Option(x), Ty::Option(y)) => self.unify(&x, &y),
            _ => Err(UnifyError::Mismatch),
        }
    }

    /// True when `a` and `b` could be unified (nothing is bound). Used to filter overload
    /// candidates.
    pub(super) fn compatible(&self, a: &Ty, b: &Ty) -> bool {
        let (a, b) = (self.shallow(a), self.shallow(b));
        match (a, b) {
            (Ty::Error, _) | (_, Ty::Error) => true,
            (Ty::Var(v), Ty::Var(w)) => {
                let (kv, kw) = (self.vars[v.0 as usize].kind, self.vars[w.0 as usize].kind);
                kv == VarKind::General || kw == VarKind::General || kv == kw
            }
            (Ty::Var(v), t) | (t, Ty::Var(v)) => {
                Self::kind_admits(self.vars[v.0 as usize].kind, &t)
            }
            (Ty::Prim(p), Ty::Prim(q)) => p == q,
            (Ty::Vector(p, n), Ty::Vector(q, m)) => p == q && n == m,
            (Ty::Ptr, Ty::Ptr) => true,
            (Ty::Adt(x), Ty::Adt(y)) => x == y,
            (Ty::Tuple(xs), Ty::Tuple(ys)) => {
                xs.len() == ys.len() && xs.iter().zip(ys.iter()).all(|(x, y)| self.compatible(x, y))
            }
            (Ty::Array(x, n), Ty::Array(y, m)) => n == m && self.compatible(&x, &y),
            (Ty::Slice(x), Ty::Slice(y))
            | (Ty::Set(x), Ty::Set(y))
            | (Ty::Option(x), Ty::Option(y)) => self.compatible(&x, &y),
            _ => false,
        }
    }

    /// Binds every unsolved literal variable to its default (`i32`, `f32`). Returns whether
    /// anything changed.
    pub(super) fn default_literals(&mut self) -> bool {
        let mut changed = false;
        for i in 0..self.vars.len() {
            if self.vars[i].bound.is_none() {
                let d = match self.vars[i].kind {
                    VarKind::Int => Ty::Prim(Prim::I32),
                    VarKind::Float => Ty::Prim(Prim::F32),
                    VarKind::General => continue,
                };
                self.vars[i].bound = Some(d);
                changed = true;
            }
        }
        changed
    }

    /// True when `t` (after following bindings) is still an unbound variable of any kind.
    pub(super) fn is_unknown(&self, t: &Ty) -> bool {
        matches!(self.shallow(t), Ty::Var(_))
    }
}
