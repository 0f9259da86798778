use scion_ir::diag::FileId;
use scion_ir::parse::parse_module;
use scion_ir::print::print_module;
use scion_ir::verify::verify;

#[test]
fn smoke() {
    let text = r#"
tree.type @AABB(low: vector<3xf32>, high: vector<3xf32>)
tree.type @BVH(bounds: !tree.adt<"AABB">) = Interior(left: !tree.adt<"BVH">, right: !tree.adt<"BVH">) | Leaf(nprims: u16, data: array<? x f32>)

func @f(%a: f32, %b: f32) -> (f32) {
  %c = "tree.add"(%a, %b) : (f32, f32) -> f32
  %k = "tree.const"() {value = -0.0} : () -> f32
  %t = "tree.cmp"(%c, %k) {pred = "lt"} : (f32, f32) -> i1
  %r = "tree.if"(%t) ({
    "tree.yield"(%a) : (f32) -> ()
  }, {
  ^bb9:
    "tree.return"(%b) : (f32) -> ()
  }) : (i1) -> f32
  "tree.return"(%r) : (f32) -> ()
}

func @g(%n: !tree.adt<"BVH">, %best: !tree.ref<tuple<f32, u32>>) -> () {
  "tree.match"(%n) ({
  ^bb1(%bb: !tree.adt<"AABB">, %l: !tree.adt<"BVH">, %r: !tree.adt<"BVH">):
    "tree.call"(%l, %best) {callee = @g} : (!tree.adt<"BVH">, !tree.ref<tuple<f32, u32>>) -> ()
    "tree.yield"() : () -> ()
  }, {
  ^bb2(%bb2: !tree.adt<"AABB">, %np: u16, %d: array<? x f32>):
    "tree.foreach"(%d) ({
    ^bb3(%e: f32):
      %old = "tree.load"(%best) : (!tree.ref<tuple<f32, u32>>) -> tuple<f32, u32>
      %o0 = "tree.extract"(%old) {index = 0} : (tuple<f32, u32>) -> f32
      %m = "tree.intrinsic"(%o0, %e) {name = "min"} : (f32, f32) -> f32
      %new = "tree.insert"(%old, %m) {index = 0} : (tuple<f32, u32>, f32) -> tuple<f32, u32>
      "tree.store"(%best, %new) : (!tree.ref<tuple<f32, u32>>, tuple<f32, u32>) -> ()
      "tree.yield"() : () -> ()
    }) : (array<? x f32>) -> ()
    "tree.yield"() : () -> ()
  }) {arms = ["Interior", "Leaf"]} : (!tree.adt<"BVH">) -> ()
  "tree.return"() : () -> ()
}
"#;
    let m = parse_module(text, FileId(0)).unwrap_or_else(|d| panic!("{:?}", d));
    verify(&m).unwrap_or_else(|e| panic!("{e}"));
    let p1 = print_module(&m);
    println!("{p1}");
    let m2 = parse_module(&p1, FileId(0)).unwrap_or_else(|d| panic!("{:?}", d));
    verify(&m2).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p1, print_module(&m2));
}
