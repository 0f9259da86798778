//! The random module generator shared by the property tests: well-formed `tree` modules with
//! arithmetic on every scalar type and special float values, `if` with yields and early
//! returns, `match` with variant and wildcard arms, `foreach`, calls (to definitions and to a
//! declaration), tuples, vectors, fields and references.

#![allow(dead_code)]

use scion_ir::module::{AdtDef, Field, Variant};
use scion_ir::tree::{CmpPred, Op};
use scion_ir::types::{FloatTy, IntTy, Type};
use scion_ir::{Builder, Module};
use scion_ir::{TypeId, ValueId};

/// A small deterministic generator (xorshift) so a failing seed reproduces.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
    pub fn chance(&mut self, percent: u64) -> bool {
        self.next() % 100 < percent
    }
}

pub struct Types {
    pub scalars: Vec<TypeId>,
    pub f32t: TypeId,
    pub u32t: TypeId,
    pub i1: TypeId,
    pub aabb: TypeId,
    pub node: TypeId,
    pub best: TypeId,
    pub data: TypeId,
    pub vec3: TypeId,
}

pub fn declare(m: &mut Module) -> Types {
    let f32t = m.types.f32();
    let f64t = m.types.float(FloatTy::F64);
    let i1 = m.types.bool();
    let u16t = m.types.int(IntTy::U16);
    let u32t = m.types.u32();
    let mut scalars = vec![f32t, f64t, i1];
    scalars.extend(IntTy::ALL.iter().map(|&t| m.types.int(t)));
    let vec3 = m.types.vector(f32t, 3);
    let data = m.types.array(f32t, None);
    let aabb = m
        .declare_adt(AdtDef {
            name: "AABB".into(),
            shared: vec![
                Field {
                    name: "low".into(),
                    ty: vec3,
                },
                Field {
                    name: "high".into(),
                    ty: vec3,
                },
            ],
            variants: vec![],
        })
        .unwrap();
    let node_ty = m.types.adt("Node");
    m.declare_adt(AdtDef {
        name: "Node".into(),
        shared: vec![Field {
            name: "bounds".into(),
            ty: aabb,
        }],
        variants: vec![
            Variant {
                name: "Inner".into(),
                fields: vec![
                    Field {
                        name: "left".into(),
                        ty: node_ty,
                    },
                    Field {
                        name: "right".into(),
                        ty: node_ty,
                    },
                ],
            },
            Variant {
                name: "Leaf".into(),
                fields: vec![
                    Field {
                        name: "n".into(),
                        ty: u16t,
                    },
                    Field {
                        name: "data".into(),
                        ty: data,
                    },
                ],
            },
            Variant {
                name: "Empty".into(),
                fields: vec![],
            },
        ],
    })
    .unwrap();
    let pair = m.types.tuple(vec![f32t, u32t]);
    let best = m.types.reference(pair);
    Types {
        scalars,
        f32t,
        u32t,
        i1,
        aabb,
        node: node_ty,
        best,
        data,
        vec3,
    }
}

const SPECIAL_FLOATS: [f64; 10] = [
    0.0,
    -0.0,
    1.5,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::NAN,
    1e-310,
    0.1,
    -3.25e20,
    f64::MAX,
];

struct Gen<'r> {
    rng: &'r mut Rng,
    t: Types,
    sigs: Vec<(String, Vec<TypeId>, Vec<TypeId>)>,
}

impl Gen<'_> {
    fn constant(&mut self, b: &mut Builder<'_>, ty: TypeId) -> ValueId {
        match b.m.types.get(ty).clone() {
            Type::Bool => b.const_bool(self.rng.chance(50)),
            Type::Int(it) => {
                let (lo, hi) = it.range();
                let v = match self.rng.below(4) {
                    0 => lo,
                    1 => hi,
                    _ => (self.rng.next() % 1000) as i128 - if it.is_signed() { 500 } else { 0 },
                };
                b.const_int(ty, v.clamp(lo, hi))
            }
            Type::Float(ft) => {
                let v = if self.rng.chance(20) {
                    // A NaN with a payload, to check exact printing of its bits.
                    f64::from_bits(
                        0x7ff0_0000_0000_0001 | (self.rng.next() & 0x000f_ffff_0000_0000),
                    )
                } else {
                    SPECIAL_FLOATS[self.rng.below(SPECIAL_FLOATS.len())]
                };
                let v = if ft == FloatTy::F32 && !v.is_nan() {
                    v as f32 as f64
                } else {
                    v
                };
                b.const_float(ty, v)
            }
            _ => unreachable!("constants are scalar"),
        }
    }

    /// A value of `ty` from the scope, or a fresh constant for scalars.
    fn value_of(&mut self, b: &mut Builder<'_>, scope: &[ValueId], ty: TypeId) -> Option<ValueId> {
        let cands: Vec<ValueId> = scope
            .iter()
            .copied()
            .filter(|&v| b.value_type(v) == ty)
            .collect();
        if !cands.is_empty() && self.rng.chance(80) {
            return Some(cands[self.rng.below(cands.len())]);
        }
        if b.m.types.is_scalar(ty) {
            Some(self.constant(b, ty))
        } else {
            None
        }
    }

    fn scalar_type(&mut self) -> TypeId {
        self.t.scalars[self.rng.below(self.t.scalars.len())]
    }

    fn body(
        &mut self,
        b: &mut Builder<'_>,
        scope: &mut Vec<ValueId>,
        depth: usize,
        results: &[TypeId],
    ) {
        let n = self.rng.below(8);
        for _ in 0..n {
            self.op(b, scope, depth, results);
        }
    }

    fn op(
        &mut self,
        b: &mut Builder<'_>,
        scope: &mut Vec<ValueId>,
        depth: usize,
        func_results: &[TypeId],
    ) {
        match self.rng.below(14) {
            0 => {
                let ty = self.scalar_type();
                scope.push(self.constant(b, ty));
            }
            1 | 2 => {
                let ty = self.scalar_type();
                let x = self.value_of(b, scope, ty).unwrap();
                let y = self.value_of(b, scope, ty).unwrap();
                let ops: &[Op] = match b.m.types.get(ty) {
                    Type::Bool => &[Op::And, Op::Or, Op::Xor],
                    Type::Int(_) => &[
                        Op::Add,
                        Op::Sub,
                        Op::Mul,
                        Op::Div,
                        Op::Rem,
                        Op::And,
                        Op::Xor,
                        Op::Shl,
                        Op::Shr,
                    ],
                    _ => &[Op::Add, Op::Sub, Op::Mul, Op::Div, Op::Rem],
                };
                let op = ops[self.rng.below(ops.len())];
                scope.push(b.binary(op, x, y));
            }
            3 => {
                let ty = self.scalar_type();
                let x = self.value_of(b, scope, ty).unwrap();
                let y = self.value_of(b, scope, ty).unwrap();
                let pred = if ty == self.t.i1 {
                    CmpPred::Ne
                } else {
                    [
                        CmpPred::Eq,
                        CmpPred::Ne,
                        CmpPred::Lt,
                        CmpPred::Le,
                        CmpPred::Gt,
                        CmpPred::Ge,
                    ][self.rng.below(6)]
                };
                let c = b.cmp(pred, x, y);
                scope.push(c);
                let z = self.value_of(b, scope, ty).unwrap();
                scope.push(b.build1(Op::Select, &[c, x, z], ty));
            }
            4 => {
                let from = self.scalar_type();
                let to = self.scalar_type();
                let x = self.value_of(b, scope, from).unwrap();
                scope.push(b.build1(Op::Cast, &[x], to));
                let neg = if b.m.types.is_integer_like(from) && from != self.t.i1 {
                    Op::BitNot
                } else if from == self.t.i1 {
                    Op::Not
                } else {
                    Op::Neg
                };
                scope.push(b.unary(neg, x));
            }
            5 if depth < 3 => {
                let c = self.value_of(b, scope, self.t.i1).unwrap();
                let ty = self.scalar_type();
                let early = self.rng.chance(25);
                let mut then_scope = scope.clone();
                let mut else_scope = scope.clone();
                // The two regions are built one after the other, then given to the op.
                let then_r = b.region(&[], |b, _| {
                    self.body(b, &mut then_scope, depth + 1, func_results);
                    if early {
                        let vals: Vec<ValueId> = func_results
                            .iter()
                            .map(|&t| self.value_of(b, &then_scope, t).unwrap())
                            .collect();
                        b.ret(&vals);
                    } else {
                        let v = self.value_of(b, &then_scope, ty).unwrap();
                        b.yield_(&[v]);
                    }
                });
                let else_r = b.region(&[], |b, _| {
                    self.body(b, &mut else_scope, depth + 1, func_results);
                    let v = self.value_of(b, &else_scope, ty).unwrap();
                    b.yield_(&[v]);
                });
                let op = b.insert(
                    scion_ir::OpSpec::new(Op::If)
                        .operands(&[c])
                        .results(&[ty])
                        .region(then_r)
                        .region(else_r),
                );
                scope.push(b.result(op, 0));
            }
            6 if depth < 3 => {
                let Some(node) = scope
                    .iter()
                    .copied()
                    .find(|&v| b.value_type(v) == self.t.node)
                else {
                    return;
                };
                let arms: &[&str] = match self.rng.below(3) {
                    0 => &["Inner", "Leaf", "Empty"],
                    1 => &["Leaf", "_"],
                    _ => &["Empty", "Inner", "Leaf"],
                };
                let ty = self.scalar_type();
                let outer = scope.clone();
                let op = b
                    .match_(node, arms, &[ty], |b, _, args| {
                        let g = &mut *self;
                        let mut s = outer.clone();
                        s.extend_from_slice(args);
                        g.body(b, &mut s, depth + 1, func_results);
                        let v = g.value_of(b, &s, ty).unwrap();
                        b.yield_(&[v]);
                    })
                    .unwrap();
                scope.push(b.result(op, 0));
            }
            7 if depth < 3 => {
                let Some(arr) = scope
                    .iter()
                    .copied()
                    .find(|&v| b.value_type(v) == self.t.data)
                else {
                    return;
                };
                let outer = scope.clone();
                b.foreach(arr, |b, e| {
                    let g = &mut *self;
                    let mut s = outer.clone();
                    s.push(e);
                    g.body(b, &mut s, depth + 1, func_results);
                    b.yield_(&[]);
                })
                .unwrap();
            }
            8 => {
                let (name, params, results) = self.sigs[self.rng.below(self.sigs.len())].clone();
                let args: Option<Vec<ValueId>> =
                    params.iter().map(|&t| self.value_of(b, scope, t)).collect();
                if let Some(args) = args {
                    let op = b.call(&name, &args, &results);
                    scope.extend(b.m.ops[op].results.iter().copied());
                }
            }
            9 => {
                let x = self.value_of(b, scope, self.t.f32t).unwrap();
                let y = self.value_of(b, scope, self.t.u32t).unwrap();
                let pair = b.m.types.tuple(vec![self.t.f32t, self.t.u32t]);
                let tup = b.insert(
                    scion_ir::OpSpec::new(Op::Tuple)
                        .operands(&[x, y])
                        .results(&[pair]),
                );
                let tup = b.result(tup, 0);
                let e = b.insert(
                    scion_ir::OpSpec::new(Op::Extract)
                        .operands(&[tup])
                        .attr("index", scion_ir::attr::Attr::Int(1))
                        .results(&[self.t.u32t]),
                );
                scope.push(tup);
                scope.push(b.result(e, 0));
            }
            10 => {
                if let Some(n) = scope
                    .iter()
                    .copied()
                    .find(|&v| b.value_type(v) == self.t.node)
                {
                    let bounds = b.field(n, "bounds").unwrap();
                    let low = b.field(bounds, "low").unwrap();
                    scope.push(bounds);
                    scope.push(low);
                } else {
                    let f = self.t.f32t;
                    let lanes: Vec<ValueId> = (0..3)
                        .map(|_| self.value_of(b, scope, f).unwrap())
                        .collect();
                    let v = b.build1(Op::Vector, &lanes, self.t.vec3);
                    let box_ = b.ctor(self.t.aabb, None, &[v, v]);
                    let node = b.ctor(self.t.node, Some("Empty"), &[box_]);
                    scope.push(v);
                    scope.push(node);
                }
            }
            11 => {
                if let Some(r) = scope
                    .iter()
                    .copied()
                    .find(|&v| b.value_type(v) == self.t.best)
                {
                    let pair = b.m.types.tuple(vec![self.t.f32t, self.t.u32t]);
                    let old = b.build1(Op::Load, &[r], pair);
                    let d = self.value_of(b, scope, self.t.f32t).unwrap();
                    let new = b.insert(
                        scion_ir::OpSpec::new(Op::Insert)
                            .operands(&[old, d])
                            .attr("index", scion_ir::attr::Attr::Int(0))
                            .results(&[pair]),
                    );
                    let new = b.result(new, 0);
                    b.build(Op::Store, &[r, new], &[]);
                }
            }
            12 => {
                if let Some(v) = scope
                    .iter()
                    .copied()
                    .find(|&v| b.value_type(v) == self.t.vec3)
                {
                    let lane = b.insert(
                        scion_ir::OpSpec::new(Op::Lane)
                            .operands(&[v])
                            .attr(
                                "index",
                                scion_ir::attr::Attr::Int(self.rng.below(3) as i128),
                            )
                            .results(&[self.t.f32t]),
                    );
                    scope.push(b.result(lane, 0));
                    let x = self.value_of(b, scope, self.t.f32t).unwrap();
                    scope.push(b.intrinsic(scion_ir::tree::Intrinsic::Min, &[x, x], self.t.f32t));
                }
            }
            _ => {
                let u = self.value_of(b, scope, self.t.u32t).unwrap();
                let bits = b.insert(
                    scion_ir::OpSpec::new(Op::Bits)
                        .operands(&[u])
                        .attr("lo", scion_ir::attr::Attr::Int(3))
                        .attr("hi", scion_ir::attr::Attr::Int(9))
                        .results(&[self.t.u32t]),
                );
                scope.push(b.result(bits, 0));
            }
        }
    }
}

pub fn random_module(seed: u64) -> Module {
    let mut rng = Rng(seed | 1);
    let mut m = Module::new();
    let t = declare(&mut m);
    let param_pool = [t.f32t, t.u32t, t.i1, t.node, t.aabb, t.best, t.data, t.vec3];
    let nfuncs = 1 + rng.below(3);
    let mut sigs = Vec::new();
    for i in 0..nfuncs {
        let np = rng.below(4);
        let params: Vec<TypeId> = (0..np)
            .map(|_| param_pool[rng.below(param_pool.len())])
            .collect();
        let results: Vec<TypeId> = if rng.chance(70) {
            vec![t.scalars[rng.below(t.scalars.len())]]
        } else {
            vec![]
        };
        sigs.push((format!("f{i}"), params, results));
    }
    let mut entries = Vec::new();
    for (name, params, results) in &sigs {
        let (f, entry) = m.add_func(name, params, results);
        if rng.chance(30) {
            m.funcs[f].attrs.set(
                "abi_name",
                scion_ir::attr::Attr::str(format!("scion_{name}")),
            );
            m.funcs[f].attrs.set("entry", scion_ir::attr::Attr::Unit);
        }
        entries.push(entry);
    }
    // A declaration (a function defined elsewhere) that bodies may call too.
    let ext_sig = ("ext".to_string(), vec![t.f32t, t.u32t], vec![t.f32t]);
    m.declare_func(&ext_sig.0, &ext_sig.1, &ext_sig.2);
    let mut callable = sigs.clone();
    callable.push(ext_sig);
    let mut g = Gen {
        rng: &mut rng,
        t,
        sigs: callable,
    };
    for ((_, _, results), entry) in sigs.iter().zip(entries) {
        let mut scope: Vec<ValueId> = m.blocks[entry].args.to_vec();
        let mut b = Builder::at_end(&mut m, entry);
        g.body(&mut b, &mut scope, 0, results);
        let vals: Vec<ValueId> = results
            .iter()
            .map(|&ty| g.value_of(&mut b, &scope, ty).unwrap())
            .collect();
        b.ret(&vals);
    }
    m
}
