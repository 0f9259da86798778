//! The parser of the text form written by [`crate::print`]: text in, [`Module`] out.
//!
//! It reads exactly the generic syntax the printer writes (plus comments, any value and block
//! names, and `-> T` for a single function result) and reports the first error as a
//! [`Diagnostic`] with a code in `E0950..E0959`, a span into the given file and a note giving the
//! line and column. It never panics, whatever the input: nesting is limited, forward
//! references are checked, and the result is a module the verifier can judge. The parser does
//! not verify: run [`crate::verify::verify`] on the result.
//!
//! Codes: `E0950` lexical error, `E0951` unexpected token, `E0952` unknown op, `E0953`
//! undefined value or block, `E0954` redefinition, `E0955` type mismatch between a value and
//! its use, `E0956` bad type, `E0957` bad attribute, `E0958` too deeply nested.

mod lexer;
mod types;

use crate::attr::{Attr, Attrs};
use crate::diag::{Diagnostic, Diagnostics, FileId, Span};
use crate::entity::{BlockId, RegionId, TypeId, ValueId};
use crate::module::{AdtDef, Block, Field, Module, ValueData, ValueDef, Variant};
use crate::op::{OpKind, Successor};
use crate::{rewrite, Builder, OpSpec};
use lexer::{Tok, Token};
use rustc_hash::{FxHashMap, FxHashSet};
use smallvec::SmallVec;

/// The deepest nesting of regions and types the parser accepts.
pub const MAX_DEPTH: usize = 64;

/// Parses a whole module. `file` is the id of `text` in the caller's
/// [`SourceMap`](crate::diag::SourceMap), used for the spans of diagnostics and of ops.
pub fn parse_module(text: &str, file: FileId) -> Result<Module, Diagnostics> {
    let toks = lexer::lex(text, file).map_err(|d| Diagnostics::from(with_position(d, text)))?;
    let mut p = Parser {
        text,
        file,
        toks,
        pos: 0,
        m: Module::new(),
        depth: 0,
        values: FxHashMap::default(),
        forward: FxHashMap::default(),
        blocks: FxHashMap::default(),
        defined_blocks: FxHashSet::default(),
        scopes: Vec::new(),
        block_scopes: Vec::new(),
    };
    match p.module() {
        Ok(()) => Ok(p.m),
        Err(d) => Err(Diagnostics::from(with_position(d, text))),
    }
}

/// Adds the 1-based line and column of the primary span as a note.
fn with_position(d: Diagnostic, text: &str) -> Diagnostic {
    let Some(span) = d.primary_span() else {
        return d;
    };
    let upto = &text.as_bytes()[..(span.start as usize).min(text.len())];
    let line = upto.iter().filter(|&&b| b == b'\n').count() + 1;
    let line_start = upto.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
    let col = text
        .get(line_start..upto.len())
        .map_or(1, |s| s.chars().count() + 1);
    d.with_note(format!("at {line}:{col}"))
}

type PResult<T> = Result<T, Diagnostic>;

struct Parser<'t> {
    text: &'t str,
    file: FileId,
    toks: Vec<Token>,
    pos: usize,
    m: Module,
    depth: usize,
    /// Value names of the current function.
    values: FxHashMap<String, ValueId>,
    /// Names used before their definition, with where they were first used.
    forward: FxHashMap<String, (ValueId, Span)>,
    /// Block names of the current function.
    blocks: FxHashMap<String, (BlockId, Span)>,
    defined_blocks: FxHashSet<BlockId>,
    /// Names defined in each open op region; they go out of scope when the region closes, so
    /// sibling regions may reuse names (as in MLIR).
    scopes: Vec<Vec<String>>,
    /// Block names first seen in each open op region; like value names they are local to it.
    block_scopes: Vec<Vec<String>>,
}

fn describe(t: &Tok) -> String {
    match t {
        Tok::Ident(s) => format!("`{s}`"),
        Tok::Bang(s) => format!("`!{s}`"),
        Tok::Value(s) => format!("`%{s}`"),
        Tok::Block(s) => format!("`^{s}`"),
        Tok::Sym(s) => format!("`@{s}`"),
        Tok::Str(s) => format!("string {s:?}"),
        Tok::Int(v) => format!("`{v}`"),
        Tok::Float(s) => format!("`{s}`"),
        Tok::Punct(c) => format!("`{c}`"),
        Tok::Arrow => "`->`".into(),
        Tok::Eof => "end of input".into(),
    }
}

impl Parser<'_> {
    fn peek(&self) -> &Tok {
        &self.toks[self.pos].tok
    }

    fn span(&self) -> Span {
        let t = &self.toks[self.pos];
        Span::new(self.file, t.start, t.end)
    }

    fn bump(&mut self) -> Token {
        let t = self.toks[self.pos].clone();
        if self.pos + 1 < self.toks.len() {
            self.pos += 1;
        }
        t
    }

    fn error(&self, code: &str, span: Span, msg: impl Into<String>) -> Diagnostic {
        Diagnostic::error(code, msg).with_primary(span, "")
    }

    fn unexpected(&self, what: &str) -> Diagnostic {
        let found = describe(self.peek());
        self.error(
            "E0951",
            self.span(),
            format!("expected {what}, found {found}"),
        )
        .with_note(format!("near `{}`", self.snippet()))
    }

    fn snippet(&self) -> String {
        let t = &self.toks[self.pos];
        let line_start = self.text[..t.start as usize]
            .rfind('\n')
            .map_or(0, |p| p + 1);
        let line_end = self.text[t.start as usize..]
            .find('\n')
            .map_or(self.text.len(), |p| p + t.start as usize);
        self.text[line_start..line_end].trim().to_string()
    }

    fn eat_punct(&mut self, c: char) -> bool {
        if *self.peek() == Tok::Punct(c) {
            self.bump();
            true
        } else {
            false
        }
    }

    fn expect_punct(&mut self, c: char) -> PResult<()> {
        if self.eat_punct(c) {
            Ok(())
        } else {
            Err(self.unexpected(&format!("`{c}`")))
        }
    }

    fn expect_arrow(&mut self) -> PResult<()> {
        if *self.peek() == Tok::Arrow {
            self.bump();
            Ok(())
        } else {
            Err(self.unexpected("`->`"))
        }
    }

    fn enter(&mut self) -> PResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.error(
                "E0958",
                self.span(),
                format!("nesting deeper than {MAX_DEPTH} levels"),
            ));
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth -= 1;
    }

    /// A name: an identifier or a quoted string.
    fn name(&mut self, what: &str) -> PResult<String> {
        match self.peek().clone() {
            Tok::Ident(s) | Tok::Str(s) => {
                self.bump();
                Ok(s)
            }
            _ => Err(self.unexpected(what)),
        }
    }

    fn module(&mut self) -> PResult<()> {
        loop {
            match self.peek().clone() {
                Tok::Eof => return Ok(()),
                Tok::Ident(s) if s == "tree.type" => self.adt_decl()?,
                Tok::Ident(s) if s == "tree.layout" => self.layout_decl()?,
                Tok::Ident(s) if s == "func" => self.func()?,
                _ => return Err(self.unexpected("`func`, `tree.type` or `tree.layout`")),
            }
        }
    }

    fn adt_decl(&mut self) -> PResult<()> {
        let start = self.span();
        self.bump();
        let Tok::Sym(name) = self.peek().clone() else {
            return Err(self.unexpected("`@Name`"));
        };
        self.bump();
        let shared = self.fields()?;
        let mut variants = Vec::new();
        if self.eat_punct('=') {
            loop {
                let vname = self.name("a variant name")?;
                let fields = self.fields()?;
                if variants.iter().any(|v: &Variant| v.name == vname) {
                    return Err(self.error(
                        "E0954",
                        start,
                        format!("variant `{vname}` declared twice in `{name}`"),
                    ));
                }
                variants.push(Variant {
                    name: vname,
                    fields,
                });
                if !self.eat_punct('|') {
                    break;
                }
            }
        }
        let def = AdtDef {
            name: name.clone(),
            shared,
            variants,
        };
        if self.m.declare_adt(def).is_err() {
            return Err(self.error("E0954", start, format!("type `{name}` declared twice")));
        }
        Ok(())
    }

    /// `tree.layout @Name [for @Type] "source"`.
    fn layout_decl(&mut self) -> PResult<()> {
        let start = self.span();
        self.bump();
        let Tok::Sym(name) = self.peek().clone() else {
            return Err(self.unexpected("`@Name`"));
        };
        self.bump();
        let adt = if matches!(self.peek(), Tok::Ident(s) if s == "for") {
            self.bump();
            let Tok::Sym(a) = self.peek().clone() else {
                return Err(self.unexpected("`@Type`"));
            };
            self.bump();
            Some(a)
        } else {
            None
        };
        let Tok::Str(source) = self.peek().clone() else {
            return Err(self.unexpected("the layout's source as a string"));
        };
        self.bump();
        if self.m.layouts.iter().any(|l| l.name == name) {
            return Err(self.error("E0954", start, format!("layout `{name}` declared twice")));
        }
        self.m
            .layouts
            .push(crate::module::LayoutSource { name, adt, source });
        Ok(())
    }

    fn fields(&mut self) -> PResult<Vec<Field>> {
        self.expect_punct('(')?;
        let mut fields: Vec<Field> = Vec::new();
        if self.eat_punct(')') {
            return Ok(fields);
        }
        loop {
            let span = self.span();
            let name = self.name("a field name")?;
            self.expect_punct(':')?;
            let ty = self.ty()?;
            if fields.iter().any(|f| f.name == name) {
                return Err(self.error("E0954", span, format!("field `{name}` declared twice")));
            }
            fields.push(Field { name, ty });
            if !self.eat_punct(',') {
                break;
            }
        }
        self.expect_punct(')')?;
        Ok(fields)
    }

    fn func(&mut self) -> PResult<()> {
        let start = self.span();
        self.bump();
        let name = match self.peek().clone() {
            Tok::Sym(s) => {
                self.bump();
                s
            }
            _ => return Err(self.unexpected("`@name`")),
        };
        if self.m.func_by_name(&name).is_some() {
            return Err(self.error("E0954", start, format!("function `@{name}` defined twice")));
        }
        self.values.clear();
        self.scopes.clear();
        self.block_scopes.clear();
        self.forward.clear();
        self.blocks.clear();
        self.defined_blocks.clear();
        // Parameters: `%name: T`, or bare types in a declaration.
        self.expect_punct('(')?;
        let mut params: Vec<(Option<String>, Span, TypeId)> = Vec::new();
        if !self.eat_punct(')') {
            loop {
                let span = self.span();
                let name = match self.peek().clone() {
                    Tok::Value(v) => {
                        self.bump();
                        self.expect_punct(':')?;
                        Some(v)
                    }
                    _ => None,
                };
                let ty = self.ty()?;
                params.push((name, span, ty));
                if !self.eat_punct(',') {
                    break;
                }
            }
            self.expect_punct(')')?;
        }
        let mut results = Vec::new();
        if *self.peek() == Tok::Arrow {
            self.bump();
            results = self.type_list_or_single()?;
        }
        let attrs = match self.peek() {
            Tok::Ident(s) if s == "attributes" => {
                self.bump();
                self.attr_dict()?
            }
            _ => Attrs::new(),
        };
        let param_tys: Vec<TypeId> = params.iter().map(|p| p.2).collect();
        let (fid, entry) = self.m.add_func(&name, &param_tys, &results);
        self.m.funcs[fid].attrs = attrs;
        self.m.func_spans.insert(fid, start);
        if *self.peek() != Tok::Punct('{') {
            // A declaration: no body.
            let body = self.m.funcs[fid].body;
            self.m.regions[body].blocks.clear();
            return Ok(());
        }
        self.defined_blocks.insert(entry);
        let args = self.m.blocks[entry].args.clone();
        for ((pname, span, _), v) in params.into_iter().zip(args) {
            let Some(pname) = pname else {
                return Err(self.error(
                    "E0951",
                    span,
                    "a parameter of a function with a body needs a name `%x: T`",
                ));
            };
            self.define_value(&pname, v, span)?;
        }
        self.expect_punct('{')?;
        let body = self.m.funcs[fid].body;
        self.block_body(entry)?;
        while let Tok::Block(_) = self.peek() {
            let b = self.block_header(body)?;
            self.block_body(b)?;
        }
        self.expect_punct('}')?;
        self.finish_func()
    }

    /// Checks that every forward reference was defined and rewrites uses of placeholders.
    fn finish_func(&mut self) -> PResult<()> {
        if let Some((name, (_, span))) = self.forward.iter().min_by_key(|(_, (_, s))| s.start) {
            return Err(self.error("E0953", *span, format!("use of undefined value `%{name}`")));
        }
        for (name, &(b, span)) in &self.blocks {
            if !self.defined_blocks.contains(&b) {
                return Err(self.error(
                    "E0953",
                    span,
                    format!("reference to undefined block `^{name}`"),
                ));
            }
        }
        rewrite::resolve_aliases(&mut self.m);
        Ok(())
    }

    /// Binds `name` to `v`; a placeholder for an earlier forward use becomes an alias of `v`.
    fn define_value(&mut self, name: &str, v: ValueId, span: Span) -> PResult<()> {
        if let Some((placeholder, _)) = self.forward.remove(name) {
            let (want, got) = (self.m.values[placeholder].ty, self.m.values[v].ty);
            if want != got {
                return Err(self.error(
                    "E0955",
                    span,
                    format!(
                        "`%{name}` is defined with type {} but was used as {}",
                        self.m.types.display(got),
                        self.m.types.display(want)
                    ),
                ));
            }
            rewrite::replace_all_uses(&mut self.m, placeholder, v);
            self.values.insert(name.to_string(), v);
            if let Some(scope) = self.scopes.last_mut() {
                scope.push(name.to_string());
            }
            return Ok(());
        }
        if self.values.contains_key(name) {
            return Err(self.error("E0954", span, format!("value `%{name}` defined twice")));
        }
        self.values.insert(name.to_string(), v);
        if let Some(scope) = self.scopes.last_mut() {
            scope.push(name.to_string());
        }
        Ok(())
    }

    /// The value `name` used with type `ty`: a defined value (types must agree) or a new
    /// placeholder for a forward reference.
    fn use_value(&mut self, name: &str, ty: TypeId, span: Span) -> PResult<ValueId> {
        if let Some(&v) = self.values.get(name) {
            let have = self.m.values[v].ty;
            if have != ty {
                return Err(self.error(
                    "E0955",
                    span,
                    format!(
                        "`%{name}` has type {} but is used as {}",
                        self.m.types.display(have),
                        self.m.types.display(ty)
                    ),
                ));
            }
            return Ok(v);
        }
        let v = self.m.values.alloc(ValueData {
            ty,
            def: ValueDef::Forward,
        });
        self.values.insert(name.to_string(), v);
        self.forward.insert(name.to_string(), (v, span));
        Ok(v)
    }

    /// The block called `name`, created (detached, without arguments) on first reference.
    fn block_ref(&mut self, name: &str, span: Span) -> BlockId {
        if let Some(&(b, _)) = self.blocks.get(name) {
            return b;
        }
        let b = self.m.blocks.alloc(Block::default());
        self.blocks.insert(name.to_string(), (b, span));
        if let Some(scope) = self.block_scopes.last_mut() {
            scope.push(name.to_string());
        }
        b
    }

    /// `^name(%a: T, ...):` — defines a block at the end of `region`.
    fn block_header(&mut self, region: RegionId) -> PResult<BlockId> {
        let span = self.span();
        let Tok::Block(name) = self.peek().clone() else {
            return Err(self.unexpected("a block label"));
        };
        self.bump();
        let b = self.block_ref(&name, span);
        if !self.defined_blocks.insert(b) {
            return Err(self.error("E0954", span, format!("block `^{name}` defined twice")));
        }
        self.m.blocks[b].parent = Some(region);
        self.m.regions[region].blocks.push(b);
        if self.eat_punct('(') {
            loop {
                let vspan = self.span();
                let Tok::Value(v) = self.peek().clone() else {
                    return Err(self.unexpected("a block argument"));
                };
                self.bump();
                self.expect_punct(':')?;
                let ty = self.ty()?;
                let arg = self.m.add_block_arg(b, ty);
                self.define_value(&v, arg, vspan)?;
                if !self.eat_punct(',') {
                    break;
                }
            }
            self.expect_punct(')')?;
        }
        self.expect_punct(':')?;
        Ok(b)
    }

    /// Ops up to the next block label or closing brace.
    fn block_body(&mut self, b: BlockId) -> PResult<()> {
        loop {
            match self.peek() {
                Tok::Block(_) | Tok::Punct('}') | Tok::Eof => return Ok(()),
                _ => self.op(b)?,
            }
        }
    }

    /// `{ [^bb(...):] ops ... }`.
    fn region(&mut self) -> PResult<RegionId> {
        self.enter()?;
        self.expect_punct('{')?;
        self.scopes.push(Vec::new());
        self.block_scopes.push(Vec::new());
        let region = self.m.new_region();
        if !matches!(self.peek(), Tok::Block(_) | Tok::Punct('}')) {
            let b = self.m.add_block(region, &[]);
            self.defined_blocks.insert(b);
            self.block_body(b)?;
        }
        while let Tok::Block(_) = self.peek() {
            let b = self.block_header(region)?;
            self.block_body(b)?;
        }
        self.expect_punct('}')?;
        for name in self.scopes.pop().unwrap_or_default() {
            self.values.remove(&name);
        }
        for name in self.block_scopes.pop().unwrap_or_default() {
            if let Some((b, span)) = self.blocks.remove(&name) {
                if !self.defined_blocks.contains(&b) {
                    return Err(self.error(
                        "E0953",
                        span,
                        format!("reference to undefined block `^{name}`"),
                    ));
                }
            }
        }
        self.leave();
        Ok(region)
    }

    fn op(&mut self, block: BlockId) -> PResult<()> {
        let start = self.span();
        let mut results: Vec<(String, Span)> = Vec::new();
        if let Tok::Value(_) = self.peek() {
            loop {
                let span = self.span();
                let Tok::Value(v) = self.peek().clone() else {
                    return Err(self.unexpected("a result `%name`"));
                };
                self.bump();
                results.push((v, span));
                if !self.eat_punct(',') {
                    break;
                }
            }
            self.expect_punct('=')?;
        }
        let name_span = self.span();
        let Tok::Str(name) = self.peek().clone() else {
            return Err(self.unexpected("an op name in quotes"));
        };
        self.bump();
        let Some(kind) = OpKind::from_name(&name) else {
            return Err(self.error("E0952", name_span, format!("unknown op `{name}`")));
        };
        // Operands: names now, types from the signature.
        self.expect_punct('(')?;
        let mut operands: Vec<(String, Span)> = Vec::new();
        if !self.eat_punct(')') {
            loop {
                let span = self.span();
                let Tok::Value(v) = self.peek().clone() else {
                    return Err(self.unexpected("an operand `%name`"));
                };
                self.bump();
                operands.push((v, span));
                if !self.eat_punct(',') {
                    break;
                }
            }
            self.expect_punct(')')?;
        }
        let mut successors = SmallVec::new();
        if self.eat_punct('[') {
            loop {
                successors.push(self.successor()?);
                if !self.eat_punct(',') {
                    break;
                }
            }
            self.expect_punct(']')?;
        }
        let mut regions = SmallVec::<[RegionId; 2]>::new();
        if *self.peek() == Tok::Punct('(') {
            self.bump();
            loop {
                regions.push(self.region()?);
                if !self.eat_punct(',') {
                    break;
                }
            }
            self.expect_punct(')')?;
        }
        let attrs = if *self.peek() == Tok::Punct('{') {
            self.attr_dict()?
        } else {
            Attrs::new()
        };
        self.expect_punct(':')?;
        let sig_span = self.span();
        self.expect_punct('(')?;
        let operand_tys = self.type_list_tail()?;
        self.expect_arrow()?;
        let result_tys = self.type_list_or_single()?;
        if operand_tys.len() != operands.len() {
            return Err(self.error(
                "E0951",
                sig_span,
                format!(
                    "{} operands but {} operand types",
                    operands.len(),
                    operand_tys.len()
                ),
            ));
        }
        if result_tys.len() != results.len() {
            return Err(self.error(
                "E0951",
                sig_span,
                format!(
                    "{} results but {} result types",
                    results.len(),
                    result_tys.len()
                ),
            ));
        }
        let mut operand_vals = SmallVec::<[ValueId; 4]>::new();
        for ((name, span), ty) in operands.iter().zip(&operand_tys) {
            operand_vals.push(self.use_value(name, *ty, *span)?);
        }
        let end = self.toks[self.pos.saturating_sub(1)].end;
        let spec = OpSpec {
            kind,
            operands: operand_vals,
            result_types: result_tys.into_iter().collect(),
            attrs,
            regions,
            successors,
        };
        let mut b = Builder::at_end(&mut self.m, block);
        b.set_span(Some(Span::new(self.file, start.start, end)));
        let op = b.insert(spec);
        let vals = self.m.ops[op].results.clone();
        for ((name, span), v) in results.into_iter().zip(vals) {
            self.define_value(&name, v, span)?;
        }
        Ok(())
    }

    /// `{name = value, ...}`
    fn attr_dict(&mut self) -> PResult<Attrs> {
        self.expect_punct('{')?;
        let mut attrs = Attrs::new();
        if self.eat_punct('}') {
            return Ok(attrs);
        }
        loop {
            let aspan = self.span();
            let aname = self.name("an attribute name")?;
            // A name alone is a unit attribute, as in MLIR (`{entry}`).
            let value = if self.eat_punct('=') {
                self.attr()?
            } else {
                Attr::Unit
            };
            if attrs.get(&aname).is_some() {
                return Err(self.error("E0957", aspan, format!("attribute `{aname}` given twice")));
            }
            attrs.set(&aname, value);
            if !self.eat_punct(',') {
                break;
            }
        }
        self.expect_punct('}')?;
        Ok(attrs)
    }

    /// `^bb(%a, %b : T, U)` or `^bb`.
    fn successor(&mut self) -> PResult<Successor> {
        let span = self.span();
        let Tok::Block(name) = self.peek().clone() else {
            return Err(self.unexpected("a successor block"));
        };
        self.bump();
        let block = self.block_ref(&name, span);
        let mut args = SmallVec::new();
        if self.eat_punct('(') {
            let mut names = Vec::new();
            loop {
                let vspan = self.span();
                let Tok::Value(v) = self.peek().clone() else {
                    return Err(self.unexpected("a value"));
                };
                self.bump();
                names.push((v, vspan));
                if !self.eat_punct(',') {
                    break;
                }
            }
            self.expect_punct(':')?;
            let mut tys = vec![self.ty()?];
            while self.eat_punct(',') {
                tys.push(self.ty()?);
            }
            self.expect_punct(')')?;
            if tys.len() != names.len() {
                return Err(self.error(
                    "E0951",
                    span,
                    format!("{} values but {} types", names.len(), tys.len()),
                ));
            }
            for ((n, s), t) in names.iter().zip(tys) {
                args.push(self.use_value(n, t, *s)?);
            }
        }
        Ok(Successor { block, args })
    }

    /// After `(`: types separated by commas up to `)`.
    fn type_list_tail(&mut self) -> PResult<Vec<TypeId>> {
        let mut tys = Vec::new();
        if self.eat_punct(')') {
            return Ok(tys);
        }
        loop {
            tys.push(self.ty()?);
            if !self.eat_punct(',') {
                break;
            }
        }
        self.expect_punct(')')?;
        Ok(tys)
    }

    /// `(T, U)`, `()` or a single `T`.
    fn type_list_or_single(&mut self) -> PResult<Vec<TypeId>> {
        if self.eat_punct('(') {
            self.type_list_tail()
        } else {
            Ok(vec![self.ty()?])
        }
    }
}
