/* replay: runs the exported entries of one `scionc --entry closest_hit --layout L` object on
 * trees and rays recorded by the Rust tests, so generated code can be checked on a machine
 * the tests cannot run Rust on (AArch64 under qemu-user: tests/tests/aarch64_qemu.rs).
 *
 * Build: cc -std=c11 -include scion_closest_hit_L.h -DLAYOUT=L replay.c L.o -o replay
 * Run:   replay IN.rply OUT.hits [IN.rply OUT.hits ...]
 *
 * IN (little-endian): "SCNRPLY2", u32 node_count, u32 root (UINT32_MAX: empty tree),
 * u32 prim_count, u32 ray_count, u32 node_size, then node_count logical nodes of node_size
 * bytes each (the layout's ScionLogical_<Type>, as the runtime's schema fill writes them),
 * prim_count ScionTriangle (40 bytes each) and ray_count scion_closest_hit_query (32 bytes).
 * OUT: ray_count scion_closest_hit_result (8 bytes: t, id), each started at (tmax, UINT32_MAX).
 * Exit status 0, or 1 with one line on stderr naming the file and what failed. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef LAYOUT
#error "define LAYOUT to the layout name (e.g. -DLAYOUT=LinearBVH)"
#endif

#define CAT3_(a, b, c) a##b##c
#define CAT3(a, b, c) CAT3_(a, b, c)
#define SIZES CAT3(scion_, LAYOUT, _sizes)
#define BUILD CAT3(scion_, LAYOUT, _build)
#define ROOT CAT3(scion_, LAYOUT, _root)
#define BATCH CAT3(scion_closest_hit_, LAYOUT, )
#define REF CAT3(scion_, LAYOUT, _ref)
#define BUFFER_COUNT CAT3(SCION_, LAYOUT, _BUFFER_COUNT)
#define BUFFER_ALIGN CAT3(SCION_, LAYOUT, _BUFFER_ALIGN)

static int fail(const char *file, const char *what) {
    fprintf(stderr, "replay: %s: %s\n", file, what);
    return 1;
}

static int read_exact(FILE *f, void *dst, size_t bytes) {
    return bytes == 0 || fread(dst, 1, bytes, f) == bytes;
}

static int replay(const char *in_path, const char *out_path) {
    FILE *f = fopen(in_path, "rb");
    if (!f) return fail(in_path, "cannot open");
    char magic[8];
    uint32_t head[5];
    if (!read_exact(f, magic, 8) || memcmp(magic, "SCNRPLY2", 8) != 0 ||
        !read_exact(f, head, sizeof head)) {
        fclose(f);
        return fail(in_path, "not a replay file");
    }
    uint32_t node_count = head[0], root = head[1], prim_count = head[2], ray_count = head[3];
    size_t node_bytes = (size_t)head[4] * node_count;
    /* 8-aligned, as ScionTreeView.nodes must be. */
    unsigned char *nodes = aligned_alloc(8, (node_bytes + 8) / 8 * 8);
    ScionTriangle *prims = malloc(sizeof *prims * (prim_count + 1));
    scion_closest_hit_query *rays = malloc(sizeof *rays * (ray_count + 1));
    scion_closest_hit_result *results = malloc(sizeof *results * (ray_count + 1));
    if (!nodes || !prims || !rays || !results) return fail(in_path, "out of memory");
    int ok = read_exact(f, nodes, node_bytes) &&
             read_exact(f, prims, sizeof *prims * prim_count) &&
             read_exact(f, rays, sizeof *rays * ray_count);
    fclose(f);
    if (!ok) return fail(in_path, "truncated");

    ScionTreeView view = {nodes, node_count, root, prims, prim_count};
    uint64_t sizes[BUFFER_COUNT];
    void *buffers[BUFFER_COUNT];
    SIZES(&view, sizes);
    for (int i = 0; i < BUFFER_COUNT; i++) {
        /* At least one aligned block, so every buffer has a real address. */
        size_t bytes = (size_t)((sizes[i] + BUFFER_ALIGN - 1) / BUFFER_ALIGN + 1) * BUFFER_ALIGN;
        buffers[i] = aligned_alloc(BUFFER_ALIGN, bytes);
        if (!buffers[i]) return fail(in_path, "out of memory for a buffer");
        memset(buffers[i], 0, bytes);
    }
    for (uint32_t i = 0; i < ray_count; i++) {
        results[i].best_0 = rays[i].ray_tmax;
        results[i].best_1 = UINT32_MAX;
    }
    if (root != UINT32_MAX) {
        int32_t status = BUILD(&view, buffers);
        if (status != SCION_OK) return fail(in_path, "the build entry returned a status");
        REF r = ROOT(&view, buffers);
        status = BATCH(buffers, rays, results, 0, ray_count, r);
        if (status != SCION_OK) return fail(in_path, "the batch entry returned a status");
    }
    FILE *out = fopen(out_path, "wb");
    if (!out) return fail(out_path, "cannot create");
    ok = ray_count == 0 || fwrite(results, sizeof *results, ray_count, out) == ray_count;
    if (fclose(out) != 0 || !ok) return fail(out_path, "cannot write");
    for (int i = 0; i < BUFFER_COUNT; i++) free(buffers[i]);
    free(nodes);
    free(prims);
    free(rays);
    free(results);
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 3 || argc % 2 == 0) {
        fprintf(stderr, "usage: %s IN.rply OUT.hits [IN.rply OUT.hits ...]\n", argv[0]);
        return 2;
    }
    for (int i = 1; i + 1 < argc; i += 2) {
        if (replay(argv[i], argv[i + 1]) != 0) return 1;
    }
    return 0;
}
