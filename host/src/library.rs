//! The library as a registry: every `library/layouts/*.scion` and `library/algorithms/*.scion`
//! (found by `build.rs`, so a new layout or algorithm is one file and no Rust), and what a
//! command line's `--layout` and `--algorithm` name: a library name or any `.scion` file.
//!
//! What the files declare is read by the front end, not kept in lists: [`declared`] compiles
//! files with the prelude to the `tree` level and reads the module's layout records (each
//! layout with the sum type the type checker chose for it), the entry functions of a known
//! [`QueryKind`] (by signature: `(ray: Ray, tree: T, best: mut (f32, u32))` is a closest hit,
//! `(a: T, b: T, pairs: mut set[(u32, u32)])` a collision,
//! `(ray, tree, hit: mut u32)` an any hit, `(p: f32x3, tree, best: mut (f32, u32, f32x3))` a
//! closest point; each with the tree type `T` it traverses) and, from a layout's build
//! functions, how it stores boxes (a build that quantizes with `quant_lo`/`quant_hi` is
//! [`Boxes::GlobalQ16`], with `sg_code_up`/`sg_code_down` [`Boxes::SnappedQ10`]; the decoded
//! tree is then the bit-for-bit reference). [`resolve_kind`] pairs a layout with an entry of a
//! kind over its type ([`resolve`]: the closest hit).
//!
//! Names: a library layout's name is its file stem with `-` for `_` (`pbrt_q16.scion` is
//! `pbrt-q16`); an algorithm's is its file stem (`closest_hit_dop14`) or a closest-hit
//! function's name. A file is `PATH.scion`, optionally `PATH.scion:NAME` to pick one of several
//! layouts (or closest hits) it declares.

use crate::mem_interp::{compile_program, Program};
use crate::quantized::Boxes;
use scion_compiler::driver::cli::Emit;
use scion_compiler::frontend::PassOptions;
use scion_ir::op::OpKind;
use scion_ir::types::Type;
use scion_ir::Module;

include!(concat!(env!("OUT_DIR"), "/library_files.rs"));

/// A library layout's command-line name: its file stem with `-` for `_`.
pub fn layout_name(stem: &str) -> String {
    stem.replace('_', "-")
}

/// The library layouts' command-line names, sorted by file stem.
pub fn layout_names() -> Vec<String> {
    LAYOUT_FILES.iter().map(|(s, _)| layout_name(s)).collect()
}

/// The library algorithms' names (file stems), sorted.
pub fn algorithm_names() -> Vec<&'static str> {
    ALGORITHM_FILES.iter().map(|(s, _)| *s).collect()
}

/// The library layout file called `name` (`pbrt-q16` or its stem `pbrt_q16`): stem and text.
pub fn layout_file(name: &str) -> Option<(&'static str, &'static str)> {
    let stem = name.replace('-', "_");
    LAYOUT_FILES.iter().find(|(s, _)| *s == stem).copied()
}

/// The library algorithm file with stem `stem`: stem and text.
pub fn algorithm_file(stem: &str) -> Option<(&'static str, &'static str)> {
    ALGORITHM_FILES.iter().find(|(s, _)| *s == stem).copied()
}

/// A layout declared in a set of files.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeclaredLayout {
    /// The layout's name in the source (`LinearBVH`).
    pub name: String,
    /// The sum type it realizes (`BVH`), as the type checker chose it.
    pub tree_type: Option<String>,
    /// How its build stores boxes.
    pub boxes: Boxes,
    /// The record type its leaves hold (`Triangle`, `Segment`), when its tree type has a
    /// primitive array.
    pub primitive: Option<String>,
    /// Children per interior node of its tree type: `n` for an array of children `T[n]`
    /// (`BVH8`: 8), else 2 (two subtree fields, `left` and `right`).
    pub arity: u32,
}

/// The kinds of query an entry answers, by its signature `(query, tree: T, result: mut R)`:
/// what `scion run` knows how to generate, start, check and write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum QueryKind {
    /// `(ray: Ray, tree, best: mut (f32, u32))`: the nearest hit's distance and primitive.
    ClosestHit,
    /// `(ray: Ray, tree, hit: mut u32)`: whether anything is hit within the ray's range.
    AnyHit,
    /// `(p: f32x3, tree, best: mut (f32, u32, f32x3))`: the nearest surface point.
    ClosestPoint,
    /// `(a: tree, b: tree, pairs: mut set[(u32, u32)])`: the colliding triangle pairs of two
    /// trees. One query over two trees, not a batch of queries over one (`scion run`'s
    /// collision path, `crate::entries::Entries::collide`).
    Collide,
}

impl QueryKind {
    /// Every kind.
    pub const ALL: [QueryKind; 4] = [
        QueryKind::ClosestHit,
        QueryKind::AnyHit,
        QueryKind::ClosestPoint,
        QueryKind::Collide,
    ];

    /// The kinds whose entries answer a batch of queries over one tree (`crate::queries`).
    pub const BATCHED: [QueryKind; 3] = [
        QueryKind::ClosestHit,
        QueryKind::AnyHit,
        QueryKind::ClosestPoint,
    ];

    /// The command-line name (`closest-hit`, `any-hit`, `closest-point`).
    pub fn name(self) -> &'static str {
        match self {
            QueryKind::ClosestHit => "closest-hit",
            QueryKind::AnyHit => "any-hit",
            QueryKind::ClosestPoint => "closest-point",
            QueryKind::Collide => "collide",
        }
    }

    /// The library function taken when several of this kind traverse the layout's type.
    pub fn preferred(self) -> &'static str {
        match self {
            QueryKind::ClosestHit => "closest_hit",
            QueryKind::AnyHit => "occluded",
            QueryKind::ClosestPoint => "closest_point_query",
            QueryKind::Collide => "collide",
        }
    }

    /// The entry's signature as source writes it.
    pub fn source_signature(self) -> &'static str {
        match self {
            QueryKind::ClosestHit => "(ray: Ray, tree: T, best: mut (f32, u32))",
            QueryKind::AnyHit => "(ray: Ray, tree: T, hit: mut u32)",
            QueryKind::ClosestPoint => "(p: f32x3, tree: T, best: mut (f32, u32, f32x3))",
            QueryKind::Collide => "(a: T, b: T, pairs: mut set[(u32, u32)])",
        }
    }

    /// The query and result types (as the `tree` level prints them) of this kind (for
    /// collision, the query is a second tree: `T`).
    fn signature(self) -> (&'static str, &'static str) {
        match self {
            QueryKind::Collide => ("T", "!tree.ref<set<tuple<u32, u32>>>"),
            QueryKind::ClosestHit => ("!tree.adt<\"Ray\">", "!tree.ref<tuple<f32, u32>>"),
            QueryKind::AnyHit => ("!tree.adt<\"Ray\">", "!tree.ref<u32>"),
            QueryKind::ClosestPoint => {
                ("vector<3xf32>", "!tree.ref<tuple<f32, u32, vector<3xf32>>>")
            }
        }
    }
}

/// What a set of files declares (with the prelude).
#[derive(Clone, Debug, Default)]
pub struct Declared {
    /// Layouts, in declaration order.
    pub layouts: Vec<DeclaredLayout>,
    /// Entry functions `(query, tree: T, result: mut R)` of a known kind: name, `T`, kind.
    pub entries: Vec<(String, String, QueryKind)>,
    /// Functions some other function calls: an entry among them is a piece of a traversal
    /// (`collide_node` of `collide`), runnable by name but never chosen by default.
    pub called: std::collections::BTreeSet<String>,
}

impl Declared {
    /// The entries of `kind`: name and tree type.
    pub fn of_kind(&self, kind: QueryKind) -> Vec<(String, String)> {
        self.entries
            .iter()
            .filter(|e| e.2 == kind)
            .map(|e| (e.0.clone(), e.1.clone()))
            .collect()
    }

    /// The entries no other function calls: the traversals themselves, not their pieces.
    pub fn roots(&self) -> Vec<(String, String, QueryKind)> {
        self.entries
            .iter()
            .filter(|e| !self.called.contains(&e.0))
            .cloned()
            .collect()
    }
}

/// Reads what `files` (name, text) declare, through the front end; errors are rendered
/// diagnostics.
pub fn declared(files: &[(String, String)]) -> Result<Declared, String> {
    let program = Program {
        files: files.to_vec(),
        layout: String::new(),
        algorithm: String::new(),
    };
    let (module, _, _) = compile_program(&program, Emit::Tree, &[], &PassOptions::default())?;
    Ok(Declared {
        layouts: module
            .layouts
            .iter()
            .map(|l| DeclaredLayout {
                name: l.name.clone(),
                tree_type: l.adt.clone(),
                boxes: build_boxes(&module, &l.name, l.adt.as_deref()),
                primitive: l.adt.as_deref().and_then(|t| primitive_of(&module, t)),
                arity: l.adt.as_deref().map_or(2, |t| arity_of(&module, t)),
            })
            .collect(),
        entries: entries(&module),
        called: called(&module),
    })
}

/// The element type of the primitive array (`data: Triangle[n]`) of sum type `adt`.
fn primitive_of(module: &Module, adt: &str) -> Option<String> {
    module
        .adt(adt)?
        .variants
        .iter()
        .flat_map(|v| &v.fields)
        .find_map(|f| match module.types.get(f.ty) {
            Type::Array { elem, len: None } => match module.types.get(*elem) {
                Type::Adt(n) => Some(n.clone()),
                _ => None,
            },
            _ => None,
        })
}

/// Children per interior node of sum type `adt`: the length of an array of `adt` in a variant
/// (`children: BVH8[8]`), else 2.
fn arity_of(module: &Module, adt: &str) -> u32 {
    let Some(def) = module.adt(adt) else {
        return 2;
    };
    def.variants
        .iter()
        .flat_map(|v| &v.fields)
        .filter_map(|f| match module.types.get(f.ty) {
            Type::Array {
                elem,
                len: Some(n),
            } if matches!(module.types.get(*elem), Type::Adt(a) if a == adt) => {
                u32::try_from(*n).ok()
            }
            _ => None,
        })
        .max()
        .unwrap_or(2)
}

/// The names of the functions that another function of `module` calls.
fn called(module: &Module) -> std::collections::BTreeSet<String> {
    let mut out = std::collections::BTreeSet::new();
    for &f in &module.func_order {
        let name = &module.funcs[f].name;
        for op in scion_ir::walk::region_ops(module, module.funcs[f].body) {
            if let Some(c) = module.ops[op].callee() {
                if c != name {
                    out.insert(c.to_string());
                }
            }
        }
    }
    out
}

/// How layout `layout` stores boxes, as far as its bit-for-bit reference goes: quantized
/// against one frame its `build root` writes from the root's box ([`Boxes::GlobalQ16`] when
/// that build calls `frame_step`, [`Boxes::SnappedQ10`] when it calls `sg_bins`); quantized per
/// node when another of its builds, or a function they call, calls `frame_step` (with codes up
/// to 255: [`Boxes::NodeQ8`], else [`Boxes::NodeQ16`]: the eight-wide `-q8`/`-q16` layouts,
/// whose decoded boxes are those of the wide tree's children, when its tree type has one interior
/// and one leaf variant: the hair BVH quantizes the oriented boxes of a second interior variant,
/// which its own test decodes); else [`Boxes::Exact`].
fn build_boxes(module: &Module, layout: &str, tree_type: Option<&str>) -> Boxes {
    use scion_ir::tree::Op as T;
    let intrinsics = |f: scion_ir::FuncId| {
        scion_ir::walk::region_ops(module, module.funcs[f].body)
            .into_iter()
            .filter(|&op| matches!(module.ops[op].kind, OpKind::Tree(T::Intrinsic)))
            .collect::<Vec<_>>()
    };
    let mut boxes = Boxes::Exact;
    let mut others = Vec::new();
    for &f in &module.func_order {
        let func = &module.funcs[f];
        if func.attrs.get("build_of").and_then(|a| a.as_str()) != Some(layout) {
            continue;
        }
        if func.attrs.get("variant").and_then(|a| a.as_str()) != Some("root") {
            others.push(f);
            continue;
        }
        for op in intrinsics(f) {
            match module.ops[op].str_attr("name") {
                Some("frame_step") => boxes = Boxes::GlobalQ16,
                Some("sg_bins") => boxes = Boxes::SnappedQ10,
                _ => {}
            }
        }
    }
    if boxes != Boxes::Exact {
        return boxes;
    }
    let two_variants = tree_type
        .and_then(|t| module.adt(t))
        .is_some_and(|d| d.variants.len() == 2);
    if !two_variants {
        return Boxes::Exact;
    }
    // The other builds and everything they call.
    let mut seen: std::collections::BTreeSet<scion_ir::FuncId> = others.iter().copied().collect();
    while let Some(f) = others.pop() {
        for op in scion_ir::walk::region_ops(module, module.funcs[f].body) {
            let o = &module.ops[op];
            if let Some(callee) = o.callee().and_then(|c| module.func_by_name(c)) {
                if seen.insert(callee) {
                    others.push(callee);
                }
            }
            if matches!(o.kind, OpKind::Tree(T::Intrinsic))
                && o.str_attr("name") == Some("frame_step")
            {
                let m = o.operands.get(2).and_then(|&v| match module.values[v].def {
                    scion_ir::module::ValueDef::Result(d, _) => module.ops[d].int_attr("value"),
                    _ => None,
                });
                return if m == Some(255) {
                    Boxes::NodeQ8
                } else {
                    Boxes::NodeQ16
                };
            }
        }
    }
    Boxes::Exact
}

/// The module's entry functions of a known [`QueryKind`]: name, tree type, kind.
fn entries(module: &Module) -> Vec<(String, String, QueryKind)> {
    module
        .func_order
        .iter()
        .filter_map(|&f| {
            let func = &module.funcs[f];
            let [query, tree, out] = func.params[..] else {
                return None;
            };
            if !func.results.is_empty() {
                return None;
            }
            let Type::Adt(t) = module.types.get(tree) else {
                return None;
            };
            // Two parameters of one sum type: the query is the second tree (`T`).
            let q = if query == tree && module.adt(t).is_some_and(|d| !d.is_record()) {
                "T".to_string()
            } else {
                module.types.display(query).to_string()
            };
            let r = module.types.display(out).to_string();
            QueryKind::ALL
                .into_iter()
                .find(|k| k.signature() == (q.as_str(), r.as_str()))
                .map(|k| (func.name.clone(), t.clone(), k))
        })
        .collect()
}

/// The program `--layout` and `--algorithm` name (a layout and an entry over its type).
#[derive(Clone, Debug)]
pub struct Resolved {
    /// The files, the layout's name and the closest hit's name.
    pub program: Program,
    /// How the layout stores boxes (its reference is the decoded tree when quantized).
    pub boxes: Boxes,
    /// The sum type the layout realizes and the entry traverses.
    pub tree_type: String,
    /// The library layout's file stem, `None` for a layout from a file.
    pub library_stem: Option<&'static str>,
    /// The record type the layout's leaves hold (`Triangle` unless its tree type says
    /// otherwise: `Segment` for strands); scenes of triangles need `Triangle`.
    pub primitive: String,
    /// Children per interior node of the tree type ([`DeclaredLayout::arity`]): which
    /// reference traversal its hits are compared with (`crate::queries::Traversed`).
    pub arity: u32,
}

/// True when `arg` names a file rather than a library entry.
fn is_file(arg: &str) -> bool {
    arg.ends_with(".scion") || arg.contains('/') || arg.contains(".scion:")
}

/// `PATH.scion[:NAME]` -> (path, name).
fn split_file(arg: &str) -> (&str, Option<&str>) {
    match arg.rsplit_once(".scion:") {
        Some((path, name)) => (&arg[..path.len() + ".scion".len()], Some(name)),
        None => (arg, None),
    }
}

fn read(path: &str) -> Result<(String, String), String> {
    std::fs::read_to_string(path)
        .map(|text| (path.to_string(), text))
        .map_err(|e| format!("cannot read {path}: {e}"))
}

/// Resolves `--layout layout` and `--algorithm algorithm` (`None`: the closest hit over the
/// layout's tree type, from the library) to a closest-hit program ([`resolve_kind`]).
pub fn resolve(layout: &str, algorithm: Option<&str>) -> Result<Resolved, String> {
    resolve_kind(layout, algorithm, QueryKind::ClosestHit)
}

/// Resolves `--layout layout` and `--algorithm algorithm` (`None`: the library's entry of
/// `kind` over the layout's tree type) to a program whose entry answers `kind`. Errors say
/// what was looked for and what exists.
pub fn resolve_kind(
    layout: &str,
    algorithm: Option<&str>,
    kind: QueryKind,
) -> Result<Resolved, String> {
    // The layout's file.
    let (layout_file, layout_pick, library_stem) = if is_file(layout) {
        let (path, pick) = split_file(layout);
        (read(path)?, pick, None)
    } else {
        let (stem, text) = layout_file(layout).ok_or_else(|| {
            format!(
                "unknown layout `{layout}`: the library's are {}; or give a .scion file",
                layout_names().join(", ")
            )
        })?;
        (
            (format!("library/layouts/{stem}.scion"), text.to_string()),
            None,
            Some(stem),
        )
    };
    // The algorithm files.
    let (algorithm_files, entry_pick): (Vec<(String, String)>, Option<String>) = match algorithm {
        Some(a) if is_file(a) => {
            let (path, pick) = split_file(a);
            (vec![read(path)?], pick.map(String::from))
        }
        Some(a) => match algorithm_file(a) {
            Some((stem, text)) => (
                vec![(format!("library/algorithms/{stem}.scion"), text.to_string())],
                None,
            ),
            // A closest-hit function of some library file.
            None => (library_algorithms(), Some(a.to_string())),
        },
        None => (library_algorithms(), None),
    };
    let mut files = algorithm_files;
    if !files.iter().any(|(n, _)| *n == layout_file.0) {
        files.push(layout_file.clone());
    }
    let found = declared(&files)?;
    // The layout: the one the layout file declares (or the one picked).
    let own = declared_in(&layout_file.1, &found.layouts);
    let chosen = match layout_pick {
        Some(name) => found
            .layouts
            .iter()
            .find(|l| l.name == name)
            .ok_or_else(|| format!("{} declares no layout `{name}`", layout_file.0))?,
        None => match own[..] {
            [one] => one,
            [] => return Err(format!("{} declares no layout", layout_file.0)),
            _ => {
                let names: Vec<&str> = own.iter().map(|l| l.name.as_str()).collect();
                return Err(format!(
                    "{} declares several layouts ({}); pick one as {}:NAME",
                    layout_file.0,
                    names.join(", "),
                    layout_file.0
                ));
            }
        },
    };
    let tree_type = chosen.tree_type.clone().ok_or_else(|| {
        format!(
            "layout `{}`: the type checker could not decide which sum type it realizes",
            chosen.name
        )
    })?;
    // The entry of that kind over that type.
    let of_kind = found.of_kind(kind);
    let what = kind.name();
    // By default, only the traversals themselves (entries no other function calls).
    let over: Vec<&(String, String)> = of_kind
        .iter()
        .filter(|(f, t)| *t == tree_type && !found.called.contains(f))
        .collect();
    // With an algorithm file of a single entry of the kind, that one (checked against the type).
    let entry_pick = match (&entry_pick, algorithm, &of_kind[..]) {
        (None, Some(_), [(only, _)]) => Some(only.clone()),
        _ => entry_pick,
    };
    let entry = match &entry_pick {
        Some(name) => {
            let (_, t) = of_kind.iter().find(|(f, _)| f == name).ok_or_else(|| {
                format!(
                    "no {what} entry `{name}` (a function {}); the library's algorithms are {}",
                    kind.source_signature(),
                    algorithm_names().join(", ")
                )
            })?;
            if *t != tree_type {
                return Err(format!(
                    "{what} entry `{name}` traverses `{t}`, but layout `{}` realizes `{tree_type}`",
                    chosen.name
                ));
            }
            name.clone()
        }
        None => match over[..] {
            [(one, _)] => one.clone(),
            [] => {
                return Err(format!(
                    "no {what} entry traverses `{tree_type}`, the type layout `{}` realizes; \
                     give one with --algorithm FILE.scion",
                    chosen.name
                ))
            }
            _ => match over.iter().find(|(f, _)| f == kind.preferred()) {
                Some((f, _)) => f.clone(),
                None => {
                    let names: Vec<&str> = over.iter().map(|(f, _)| f.as_str()).collect();
                    return Err(format!(
                        "several {what} entries traverse `{tree_type}` ({}); pick one with \
                         --algorithm",
                        names.join(", ")
                    ));
                }
            },
        },
    };
    // Compile only the file that defines the entry, the layout's file and the files the
    // layout's type comes from (kept whole when the entry's file cannot be told by its text).
    let defines = |text: &str, what: &str| {
        text.lines().any(|l| {
            let l = l.trim_start();
            l.strip_prefix(what).is_some_and(|rest| {
                rest.starts_with('(') || rest.starts_with(' ') || rest.starts_with('=')
            })
        })
    };
    let needed: Vec<(String, String)> = files
        .iter()
        .filter(|(n, text)| {
            *n == layout_file.0
                || defines(text, &format!("func {entry}"))
                || defines(text, &format!("type {tree_type}"))
        })
        .cloned()
        .collect();
    let program = Program {
        files: needed,
        layout: chosen.name.clone(),
        algorithm: entry,
    };
    Ok(Resolved {
        program,
        boxes: chosen.boxes,
        tree_type,
        library_stem,
        primitive: chosen
            .primitive
            .clone()
            .unwrap_or_else(|| "Triangle".to_string()),
        arity: chosen.arity,
    })
}

/// The library's algorithm files, as (name, text).
/// Every entry of a known kind the library's algorithm files declare that no other function
/// calls: name, tree type, kind (`closest_hit`, `closest_point_query`,
/// `closest_point_best_first`, `collide`, `collide_recursive`, ...).
pub fn library_entries() -> Result<Vec<(String, String, QueryKind)>, String> {
    Ok(declared(&library_algorithms())?.roots())
}

fn library_algorithms() -> Vec<(String, String)> {
    ALGORITHM_FILES
        .iter()
        .map(|(s, t)| (format!("library/algorithms/{s}.scion"), t.to_string()))
        .collect()
}

/// The layouts of `all` whose declaration is in `text`.
fn declared_in<'a>(text: &str, all: &'a [DeclaredLayout]) -> Vec<&'a DeclaredLayout> {
    all.iter()
        .filter(|l| {
            text.lines().any(|line| {
                line.trim_start()
                    .starts_with(&format!("layout {}(", l.name))
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_library_files_are_found() {
        let names = layout_names();
        for n in [
            "pbrt",
            "ptr",
            "pbrt-q16",
            "sg-eq",
            "hair-bvh",
            "dop14-split",
        ] {
            assert!(names.contains(&n.to_string()), "{n} in {names:?}");
        }
        assert!(algorithm_names().contains(&"closest_hit"));
    }

    #[test]
    fn every_library_layout_pairs_with_the_closest_hit_over_its_type() {
        let want = [
            ("pbrt", "LinearBVH", "closest_hit", Boxes::Exact),
            ("pbrt-q16", "PbrtQ16", "closest_hit", Boxes::GlobalQ16),
            ("sg-eq", "SgEq", "closest_hit", Boxes::SnappedQ10),
            ("dop14-split", "DopSplit", "closest_hit_dop14", Boxes::Exact),
            ("hair-bvh", "HairBVH", "closest_hit_hair", Boxes::Exact),
            ("bvh8", "Bvh8", "closest_hit8", Boxes::Exact),
            ("bvh8-q8-ci", "Bvh8Q8CI", "closest_hit8", Boxes::NodeQ8),
            ("bvh8-q16", "Bvh8Q16", "closest_hit8", Boxes::NodeQ16),
        ];
        for (name, layout, entry, boxes) in want {
            let r = resolve(name, None).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(r.program.layout, layout);
            assert_eq!(r.program.algorithm, entry);
            assert_eq!(r.boxes, boxes, "{name}");
            assert!(r.library_stem.is_some());
        }
        for stem in LAYOUT_FILES.iter().map(|(s, _)| s) {
            resolve(stem, None).unwrap_or_else(|e| panic!("{stem}: {e}"));
        }
    }

    #[test]
    fn every_query_kind_finds_its_library_entry() {
        let r = resolve_kind("pbrt", None, QueryKind::ClosestPoint).unwrap();
        assert_eq!(r.program.algorithm, "closest_point_query");
        let r = resolve_kind(
            "ptr",
            Some("closest_point_best_first"),
            QueryKind::ClosestPoint,
        )
        .unwrap();
        assert_eq!(
            (r.program.layout.as_str(), r.tree_type.as_str()),
            ("PtrBVH", "BVH")
        );
        let r = resolve_kind("sg-eq", None, QueryKind::AnyHit).unwrap();
        assert_eq!(r.program.algorithm, "occluded");
        // Only the files needed are compiled: the entry's and the layout's.
        assert_eq!(
            r.program.files.len(),
            2,
            "{:?}",
            r.program.files.iter().map(|f| &f.0).collect::<Vec<_>>()
        );
        let r = resolve_kind("dop14-split", None, QueryKind::ClosestPoint).unwrap();
        assert_eq!(r.program.algorithm, "closest_point_dop14");
        let e = resolve_kind("dop14-split", None, QueryKind::Collide).unwrap_err();
        assert!(e.contains("no collide entry traverses `DopBVH`"), "{e}");
    }

    #[test]
    fn bad_names_and_mismatches_are_explained() {
        let e = resolve("btree", None).unwrap_err();
        assert!(
            e.contains("unknown layout `btree`") && e.contains("pbrt-q16"),
            "{e}"
        );
        let e = resolve("pbrt", Some("closest_hit_hair")).unwrap_err();
        assert!(
            e.contains("traverses `Hair`") && e.contains("realizes `BVH`"),
            "{e}"
        );
        let e = resolve("pbrt", Some("nope")).unwrap_err();
        assert!(e.contains("no closest-hit entry `nope`"), "{e}");
        let e = resolve("/nonexistent/x.scion", None).unwrap_err();
        assert!(e.contains("cannot read /nonexistent/x.scion"), "{e}");
    }
}
