"""The FCPW peer of closest-point queries (issue 16): FCPW's Python package (pip `fcpw`, its C++
core) on the same triangles and points as `scion run --algorithm closest-point` and the
`closest_point` benchmark (bench/benches/closest_point.rs writes them: 40-byte triangles, 9 f32
corners and a u32 face id; 12-byte points).

One scene object of the triangles (three vertices each), built with FCPW's surface-area BVH,
vectorized (its fastest CPU path) or not; `find_closest_points` over all points at once,
timed by the paper's method (one warm-up, RUNS runs, the mean of the middle ones). Run it on one
core (`taskset -c 0`, as scripts/bench-closest-point.sh does) for one thread. Prints
`fcpw-vectorized ms M` (or `fcpw-scalar`) and writes 20-byte results (f32 distance, u32 face
id, f32 x, y, z) to OUT.

Usage: python3 fcpw_closest.py TRIS POINTS RUNS OUT [scalar]
"""
import sys
import time

import numpy as np
import fcpw


def main():
    if len(sys.argv) not in (5, 6):
        print(__doc__, file=sys.stderr)
        return 2
    tris_path, points_path, runs, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
    vectorize = not (len(sys.argv) == 6 and sys.argv[5] == "scalar")
    raw = np.fromfile(tris_path, dtype=np.uint8)
    if raw.size % 40:
        print(f"{tris_path}: not whole 40-byte triangles", file=sys.stderr)
        return 1
    recs = raw.reshape(-1, 40)
    corners = recs[:, :36].copy().view(np.float32).reshape(-1, 3)
    ids = recs[:, 36:40].copy().view(np.uint32).reshape(-1)
    n = ids.size
    positions = np.asfortranarray(corners.astype(np.float32))
    indices = np.asfortranarray(np.arange(3 * n, dtype=np.int32).reshape(-1, 3))
    points = np.asfortranarray(np.fromfile(points_path, dtype=np.float32).reshape(-1, 3))
    q = points.shape[0]

    scene = fcpw.scene_3D()
    scene.set_object_count(1)
    scene.set_object_vertices(positions, 0)
    scene.set_object_triangles(indices, 0)
    scene.build(fcpw.aggregate_type.bvh_surface_area, vectorize)
    radii = np.full(q, np.inf, dtype=np.float32)

    def once():
        interactions = fcpw.interaction_3D_list()
        scene.find_closest_points(points, radii, interactions)
        return interactions

    result = once()  # warm-up
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        result = once()
        times.append(time.perf_counter() - t)
    times.sort()
    drop = (runs - 1) // 4
    mid = times[drop:runs - drop]
    ms = 1e3 * sum(mid) / len(mid)

    rec = np.zeros((q, 5), dtype=np.float32)
    for i, it in enumerate(result):
        p = np.array(it.p, dtype=np.float32).reshape(-1)
        rec[i, 0] = it.d
        rec[i, 1] = np.array([ids[it.primitive_index] if it.primitive_index >= 0 else 0xFFFFFFFF],
                             dtype=np.uint32).view(np.float32)[0]
        rec[i, 2:5] = p[:3]
    rec.tofile(out)
    print(f"fcpw-{'vectorized' if vectorize else 'scalar'} ms {ms:.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
