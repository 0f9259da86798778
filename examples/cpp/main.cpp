// Scion from C++: trace closest hits through a layout compiled by `scionc -O3 --emit=obj`.
//
// Loads an OBJ scene and builds its logical BVH with the runtime's C library
// (libscion_runtime.a), packs it into layout SCION_LAYOUT with the generated entry points
// (scion_L_sizes, scion_L_build, scion_L_root; one allocation per buffer, aligned to
// SCION_L_BUFFER_ALIGN), traces the primary (or secondary) rays of `scion trace` with scion_A_L (A: closest_hit
// by default) split into ranges over std::threads, prints `checksum: ...` (the number `scion trace`
// prints) and checks every hit against the runtime's reference. Exit status: 0 when every hit
// matches, 1 on a mismatch or an error (also out of memory), 2 for bad arguments.
//
// Usage: trace SCENE.obj [N rays = 65536, 1..2^32] [SEED = 1] [THREADS = 4, 1..1024]
//              [RAYS = primary | secondary]
// Built by the Makefile next to this file, which passes -DSCION_LAYOUT=<layout name>,
// -DSCION_ENTRY=<closest-hit function> (default closest_hit), -DSCION_TREE=<its tree type>
// (default BVH) and -DSCION_HEADER="<header of scionc --emit=header>". Any closest hit whose
// query is a Ray and whose result is (t, id) fits: closest_hit8 over BVH8 for the eight-wide
// layouts.

#include <cerrno>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <thread>
#include <vector>

#include "scion_runtime.h"
#include SCION_HEADER

#ifndef SCION_ENTRY
#define SCION_ENTRY closest_hit
#endif
#ifndef SCION_TREE
#define SCION_TREE BVH
#endif

#define SCION_CAT4(a, b, c, d) a##b##c##d
#define SCION_XCAT4(a, b, c, d) SCION_CAT4(a, b, c, d)
// scion_<L>_<what>, SCION_<L>_<what>, scion_<A>_<L>, scion_<A>_query, scion_logical_<T>.
#define LAYOUT_FN(what) SCION_XCAT4(scion_, SCION_LAYOUT, _, what)
#define LAYOUT_MACRO(what) SCION_XCAT4(SCION_, SCION_LAYOUT, _, what)
#define BATCH_FN SCION_XCAT4(scion_, SCION_ENTRY, _, SCION_LAYOUT)
#define LAYOUT_REF SCION_XCAT4(scion_, SCION_LAYOUT, _ref, )
#define QUERY SCION_XCAT4(scion_, SCION_ENTRY, _query, )
#define RESULT SCION_XCAT4(scion_, SCION_ENTRY, _result, )
#define LOGICAL_TREE SCION_XCAT4(scion_logical_, SCION_TREE, , )

namespace {

// The query record of the closest hit is a Ray: the runtime's rays are passed as they are.
static_assert(sizeof(QUERY) == sizeof(ScionRay), "query record is a ray");
static_assert(offsetof(QUERY, ray_tmax) == offsetof(ScionRay, tmax), "tmax");
static_assert(offsetof(QUERY, ray_direction_x) == offsetof(ScionRay, dir),
              "direction");
static_assert(sizeof(RESULT) == 8, "result record is (t, id)");

constexpr std::size_t kBuffers = LAYOUT_MACRO(BUFFER_COUNT);
constexpr std::size_t kAlign = LAYOUT_MACRO(BUFFER_ALIGN);

int fail(const char *what, const char *detail) {
    std::fprintf(stderr, "trace: %s: %s\n", what, detail);
    return 1;
}

// A decimal number in [lo, hi]; anything else (a sign, other characters, overflow) ends the
// program with status 2 and a message naming the argument.
std::uint64_t parse(const char *s, const char *what, std::uint64_t lo, std::uint64_t hi) {
    char *end = nullptr;
    errno = 0;
    unsigned long long v = std::strtoull(s, &end, 10);
    if (end == s || *end != '\0' || s[0] == '-' || s[0] == '+' || errno == ERANGE || v < lo ||
        v > hi) {
        std::fprintf(stderr, "trace: %s: `%s` is not a number from %" PRIu64 " to %" PRIu64 "\n",
                     what, s, lo, hi);
        std::exit(2);
    }
    return v;
}

int run(int argc, char **argv);

}  // namespace

int main(int argc, char **argv) {
    if (argc < 2 || argc > 6) {
        std::fprintf(stderr, "usage: %s SCENE.obj [N] [SEED] [THREADS] [primary|secondary]\n",
                     argv[0]);
        return 2;
    }
    // Nothing escapes as an uncaught exception: memory for the rays and results, and threads,
    // are the standard library's to refuse.
    try {
        return run(argc, argv);
    } catch (const std::bad_alloc &) {
        return fail("out of memory", "the rays and results do not fit; trace fewer rays (N)");
    } catch (const std::exception &e) {
        return fail("error", e.what());
    }
}

namespace {

int run(int argc, char **argv) {
    const std::uint64_t n = argc > 2 ? parse(argv[2], "N", 1, std::uint64_t{1} << 32) : 65536;
    const std::uint64_t seed = argc > 3 ? parse(argv[3], "SEED", 0, UINT64_MAX) : 1;
    const unsigned threads =
        argc > 4 ? static_cast<unsigned>(parse(argv[4], "THREADS", 1, 1024)) : 4;
    char err[512];

    ScionScene *scene = nullptr;
    if (scion_scene_load(argv[1], &scene, err, sizeof err) != SCION_RT_OK) {
        return fail("loading the scene", err);
    }
    ScionTree *tree = nullptr;
    if (scion_tree_build(scene, 0, &tree, err, sizeof err) != SCION_RT_OK) {
        return fail("building the tree", err);
    }
    // The tree's nodes in the shape the layout's constructor reads: the prelude's `BVH`, whose
    // node struct and schema the generated header declares.
    ScionTreeView view;
    if (scion_tree_view(tree, &LOGICAL_TREE, &view, err, sizeof err) != SCION_RT_OK) {
        return fail("viewing the tree", err);
    }

    // Pack: one buffer per entry of the layout's plan, each aligned to the plan's alignment.
    std::uint64_t sizes[kBuffers];
    LAYOUT_FN(sizes)(&view, sizes);
    void *buffers[kBuffers];
    for (std::size_t i = 0; i < kBuffers; ++i) {
        std::size_t bytes = (static_cast<std::size_t>(sizes[i]) + kAlign - 1) / kAlign * kAlign;
        buffers[i] = std::aligned_alloc(kAlign, bytes == 0 ? kAlign : bytes);
        if (buffers[i] == nullptr) {
            return fail("allocating a buffer", std::to_string(bytes).c_str());
        }
        std::memset(buffers[i], 0, bytes == 0 ? kAlign : bytes);
    }
    std::int32_t status = LAYOUT_FN(build)(&view, buffers);
    if (status != SCION_OK) {
        return fail("packing the tree", ("status " + std::to_string(status)).c_str());
    }
    const LAYOUT_REF root = LAYOUT_FN(root)(&view, buffers);

    // The rays of `scion trace --rays primary|secondary --n N --seed SEED`.
    const std::string kind = argc > 5 ? argv[5] : "primary";
    if (kind != "primary" && kind != "secondary") {
        return fail("rays", ("`" + kind + "` is not primary or secondary").c_str());
    }
    std::vector<ScionRay> rays(n);
    const auto make = kind == "primary" ? scion_primary_rays : scion_secondary_rays;
    if (make(scene, n, seed, rays.data(), err, sizeof err) != SCION_RT_OK) {
        return fail("generating rays", err);
    }
    std::vector<RESULT> results(n);
    for (std::uint64_t i = 0; i < n; ++i) {
        results[i].best_0 = rays[i].tmax;
        results[i].best_1 = UINT32_MAX;
    }
    const auto *queries = reinterpret_cast<const QUERY *>(rays.data());

    // Trace: the rays split into one contiguous range per thread. An empty tree has no packed
    // node to start from: every ray misses, and the results stay as initialized.
    const unsigned parts = view.node_count == 0 ? 0 : (threads == 0 ? 1 : threads);
    std::vector<std::int32_t> statuses(parts, SCION_OK);
    std::vector<std::thread> pool;
    for (unsigned p = 0; p < parts; ++p) {
        const std::uint64_t begin = n * p / parts;
        const std::uint64_t end = n * (p + 1) / parts;
        pool.emplace_back([&, p, begin, end] {
            statuses[p] = BATCH_FN(buffers, queries, results.data(), begin, end, root);
        });
    }
    for (auto &t : pool) {
        t.join();
    }
    for (unsigned p = 0; p < parts; ++p) {
        if (statuses[p] != SCION_OK) {
            return fail("tracing", ("status " + std::to_string(statuses[p]) +
                                    (statuses[p] == SCION_STACK_OVERFLOW ? " (stack overflow)" : ""))
                                       .c_str());
        }
    }

    std::vector<ScionHit> hits(n);
    std::uint64_t hit_count = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
        hits[i] = scion_hit_from_best(results[i].best_0, results[i].best_1);
        hit_count += hits[i].prim != UINT32_MAX;
    }
    std::printf("scene: %s (%" PRIu64 " triangles)\n", argv[1], scion_scene_triangle_count(scene));
    std::printf("rays: %" PRIu64 ", hits: %" PRIu64 "\n", n, hit_count);
    std::printf("checksum: %016" PRIx64 "\n", scion_hits_checksum(hits.data(), n));

    // Cross-check every hit against the runtime's reference, bit for bit.
    std::vector<ScionHit> want(n);
    if (scion_reference_closest_hits(tree, rays.data(), n, 0, want.data(), err, sizeof err) !=
        SCION_RT_OK) {
        return fail("tracing the reference", err);
    }
    std::uint64_t mismatches = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
        if (std::memcmp(&hits[i], &want[i], sizeof(ScionHit)) != 0) {
            if (mismatches < 5) {
                std::fprintf(stderr, "ray %" PRIu64 ": got (%g, %u), reference (%g, %u)\n", i,
                             static_cast<double>(hits[i].t), hits[i].prim,
                             static_cast<double>(want[i].t), want[i].prim);
            }
            ++mismatches;
        }
    }
    std::printf("mismatches: %" PRIu64 "\n", mismatches);

    for (void *b : buffers) {
        std::free(b);
    }
    scion_tree_free(tree);
    scion_scene_free(scene);
    return mismatches == 0 ? 0 : 1;
}

}  // namespace
