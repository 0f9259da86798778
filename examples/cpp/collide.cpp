// Scion from C++: collision detection through a layout compiled by `scionc -O3 --emit=obj
// --entry collide` (library/algorithms/collide.scion: two trees traversed together).
//
// Loads an OBJ scene and its copy turned by (60, 70, 10) degrees about the centre of its box
// (scion_scene_rotated, as `scion run --algorithm collide` does), builds both logical BVHs
// with the runtime's C library, packs each into layout SCION_LAYOUT with the generated entry
// points, and runs the collision entry once over both trees: its result record is a sink
// (pairs_data, pairs_capacity, pairs_count), and when the count exceeds the capacity the
// program runs it again with an array that large. Prints the number of pairs and checks them,
// sorted, against the runtime's reference (scion_reference_collide). Exit status: 0 when the
// pairs match, 1 on a mismatch or an error, 2 for bad arguments.
//
// Usage: collide SCENE.obj [CAPACITY = 1024 pairs at first]
// Built by the Makefile next to this file (`make collide` / `make run-collide`), which passes
// -DSCION_LAYOUT=<layout name> and -DSCION_HEADER="<header of scionc --emit=header --entry
// collide>".

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "scion_runtime.h"
#include SCION_HEADER

#define SCION_CAT4(a, b, c, d) a##b##c##d
#define SCION_XCAT4(a, b, c, d) SCION_CAT4(a, b, c, d)
#define LAYOUT_FN(what) SCION_XCAT4(scion_, SCION_LAYOUT, _, what)
#define LAYOUT_MACRO(what) SCION_XCAT4(SCION_, SCION_LAYOUT, _, what)
#define COLLIDE_FN SCION_XCAT4(scion_collide_, SCION_LAYOUT, , )
#define LAYOUT_REF SCION_XCAT4(scion_, SCION_LAYOUT, _ref, )

namespace {

static_assert(sizeof(scion_collide_result) == 24, "the result record is a sink");
static_assert(offsetof(scion_collide_result, pairs_count) == 16, "pairs_count");

constexpr std::size_t kBuffers = LAYOUT_MACRO(BUFFER_COUNT);
constexpr std::size_t kAlign = LAYOUT_MACRO(BUFFER_ALIGN);

int fail(const char *what, const char *detail) {
    std::fprintf(stderr, "collide: %s: %s\n", what, detail);
    return 1;
}

// One scene's logical tree packed into the layout.
struct Packed {
    ScionTree *tree = nullptr;
    void *buffers[kBuffers] = {};
    LAYOUT_REF root{};
    bool empty = true;

    ~Packed() {
        for (void *b : buffers) {
            std::free(b);
        }
        scion_tree_free(tree);
    }

    // Builds, views and packs `scene`; an error message on failure.
    std::string pack(const ScionScene *scene) {
        char err[512];
        if (scion_tree_build(scene, 0, &tree, err, sizeof err) != SCION_RT_OK) {
            return std::string("building the tree: ") + err;
        }
        ScionTreeView view;
        if (scion_tree_view(tree, &scion_logical_BVH, &view, err, sizeof err) != SCION_RT_OK) {
            return std::string("viewing the tree: ") + err;
        }
        std::uint64_t sizes[kBuffers];
        LAYOUT_FN(sizes)(&view, sizes);
        for (std::size_t i = 0; i < kBuffers; ++i) {
            std::size_t bytes = (static_cast<std::size_t>(sizes[i]) + kAlign - 1) / kAlign * kAlign;
            bytes = bytes == 0 ? kAlign : bytes;
            buffers[i] = std::aligned_alloc(kAlign, bytes);
            if (buffers[i] == nullptr) {
                return "allocating a buffer of " + std::to_string(bytes) + " bytes";
            }
            std::memset(buffers[i], 0, bytes);
        }
        std::int32_t status = LAYOUT_FN(build)(&view, buffers);
        if (status != SCION_OK) {
            return "packing the tree: status " + std::to_string(status);
        }
        root = LAYOUT_FN(root)(&view, buffers);
        empty = view.node_count == 0;
        return "";
    }
};

int run(const char *path, std::uint64_t capacity) {
    char err[512];
    ScionScene *scene = nullptr;
    if (scion_scene_load(path, &scene, err, sizeof err) != SCION_RT_OK) {
        return fail("loading the scene", err);
    }
    ScionScene *copy = nullptr;
    if (scion_scene_rotated(scene, 60.0, 70.0, 10.0, &copy, err, sizeof err) != SCION_RT_OK) {
        return fail("turning the copy", err);
    }
    Packed a, b;
    for (auto [p, s] : {std::pair<Packed *, ScionScene *>{&a, scene}, {&b, copy}}) {
        std::string why = p->pack(s);
        if (!why.empty()) {
            return fail("packing", why.c_str());
        }
    }

    // One collision over both trees; a sink too small is run again with the count it reported.
    std::vector<std::uint32_t> pairs;
    scion_collide_result sink{};
    int calls = 0;
    const auto start = std::chrono::steady_clock::now();
    if (!a.empty && !b.empty) {
        do {
            pairs.assign(2 * capacity, 0);
            sink.pairs_data = pairs.data();
            sink.pairs_capacity = capacity;
            sink.pairs_count = 0;
            scion_collide_query none{};
            std::int32_t status = COLLIDE_FN(a.buffers, &none, &sink, 0, 1, a.root, b.buffers, b.root);
            ++calls;
            if (status != SCION_OK) {
                return fail("colliding", ("status " + std::to_string(status) +
                                          (status == SCION_STACK_OVERFLOW ? " (stack overflow)" : ""))
                                             .c_str());
            }
            capacity = std::max(capacity, sink.pairs_count);
        } while (sink.pairs_count > sink.pairs_capacity);
    }
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    std::vector<std::pair<std::uint32_t, std::uint32_t>> got(sink.pairs_count);
    for (std::uint64_t i = 0; i < sink.pairs_count; ++i) {
        got[i] = {pairs[2 * i], pairs[2 * i + 1]};
    }
    std::sort(got.begin(), got.end());
    got.erase(std::unique(got.begin(), got.end()), got.end());
    std::printf("scene: %s (%" PRIu64 " triangles, and as many in the copy)\n", path,
                scion_scene_triangle_count(scene));
    std::printf("pairs: %zu (%d call%s, %.3f ms)\n", got.size(), calls, calls == 1 ? "" : "s", ms);

    // The reference's pairs, through the same kind of sink.
    std::uint64_t count = 0;
    if (scion_reference_collide(scene, copy, nullptr, 0, &count, err, sizeof err) != SCION_RT_OK) {
        return fail("the reference", err);
    }
    std::vector<std::uint32_t> want(2 * count);
    if (scion_reference_collide(scene, copy, reinterpret_cast<std::uint32_t(*)[2]>(want.data()),
                                count, &count, err, sizeof err) != SCION_RT_OK) {
        return fail("the reference", err);
    }
    std::uint64_t mismatches = got.size() == count ? 0 : 1;
    for (std::uint64_t i = 0; mismatches == 0 && i < count; ++i) {
        mismatches += got[i].first != want[2 * i] || got[i].second != want[2 * i + 1];
    }
    std::printf("reference pairs: %" PRIu64 "\n", count);
    std::printf("mismatches: %" PRIu64 "\n", mismatches);
    scion_scene_free(copy);
    scion_scene_free(scene);
    return mismatches == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char **argv) {
    if (argc < 2 || argc > 3) {
        std::fprintf(stderr, "usage: %s SCENE.obj [CAPACITY]\n", argv[0]);
        return 2;
    }
    std::uint64_t capacity = 1024;
    if (argc == 3) {
        char *end = nullptr;
        errno = 0;
        unsigned long long v = std::strtoull(argv[2], &end, 10);
        if (end == argv[2] || *end != '\0' || argv[2][0] == '-' || errno == ERANGE ||
            v > (std::uint64_t{1} << 32)) {
            std::fprintf(stderr, "collide: CAPACITY: `%s` is not a number from 0 to 2^32\n",
                         argv[2]);
            return 2;
        }
        capacity = v;
    }
    try {
        return run(argv[1], capacity);
    } catch (const std::bad_alloc &) {
        return fail("out of memory", "the pairs do not fit");
    } catch (const std::exception &e) {
        return fail("error", e.what());
    }
}
