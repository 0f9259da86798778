// The FCL peer of collision detection (issue 16): FCL 0.7 (Debian's libfcl-dev) colliding two
// triangle meshes exhaustively, with OBBRSS and with AABB bounding volumes, on the same inputs
// `scion run --algorithm collide` uses: the scene's triangles and its rotated copy, written by
// `collide_inputs` (bench/src/bin/collide_inputs.rs) as 40-byte records (9 f32 corners, u32
// face id), each mesh its own model with the identity transform.
//
// FCL builds each model with its defaults (BVSplitter, mean split, one triangle per leaf) and
// `collide` with num_max_contacts = every pair and no contact points. Timed by the paper's
// method: one warm-up, RUNS runs, the mean of the middle ones (dropping the (RUNS - 1) / 4
// fastest and slowest). Prints one line per bounding volume:
//   fcl-obbrss build_ms B collide_ms C pairs N
// and writes the sorted pairs (u32 face id in A, u32 face id in B; docs/formats.md) to
// OUT-obbrss.pairs and OUT-aabb.pairs.
//
// Usage: fcl_collide A.tris B.tris RUNS OUT
// Built by scripts/bench-collide.sh: g++ -O3 -std=c++17 -I/usr/include/eigen3 ... -lfcl

#include <fcl/fcl.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace {

struct Tri {
    float p[9];
    std::uint32_t id;
};
static_assert(sizeof(Tri) == 40, "the runtime's 40-byte triangle");

std::vector<Tri> read_tris(const char *path) {
    std::ifstream f(path, std::ios::binary);
    if (!f) {
        std::fprintf(stderr, "fcl_collide: cannot read %s\n", path);
        std::exit(1);
    }
    std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    if (bytes.size() % sizeof(Tri) != 0) {
        std::fprintf(stderr, "fcl_collide: %s is not whole 40-byte triangles\n", path);
        std::exit(1);
    }
    std::vector<Tri> tris(bytes.size() / sizeof(Tri));
    std::memcpy(tris.data(), bytes.data(), bytes.size());
    return tris;
}

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

template <typename BV>
std::shared_ptr<fcl::BVHModel<BV>> model(const std::vector<Tri> &tris) {
    std::vector<fcl::Vector3d> ps;
    std::vector<fcl::Triangle> ts;
    ps.reserve(3 * tris.size());
    ts.reserve(tris.size());
    for (std::size_t i = 0; i < tris.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
            ps.emplace_back(tris[i].p[3 * k], tris[i].p[3 * k + 1], tris[i].p[3 * k + 2]);
        }
        ts.emplace_back(3 * i, 3 * i + 1, 3 * i + 2);
    }
    auto m = std::make_shared<fcl::BVHModel<BV>>();
    m->beginModel(static_cast<int>(ts.size()), static_cast<int>(ps.size()));
    m->addSubModel(ps, ts);
    m->endModel();
    return m;
}

template <typename BV>
void run(const char *name, const std::vector<Tri> &a, const std::vector<Tri> &b, int runs,
         const std::string &out) {
    auto t = Clock::now();
    auto ma = model<BV>(a);
    auto mb = model<BV>(b);
    const double build_ms = ms_since(t);
    fcl::CollisionObjectd oa(ma, fcl::Transform3d::Identity());
    fcl::CollisionObjectd ob(mb, fcl::Transform3d::Identity());
    fcl::CollisionRequestd request(a.size() * b.size() + 1, false);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
    auto once = [&] {
        fcl::CollisionResultd result;
        fcl::collide(&oa, &ob, request, result);
        std::vector<fcl::Contactd> contacts;
        result.getContacts(contacts);
        pairs.clear();
        for (const auto &c : contacts) {
            pairs.emplace_back(a[static_cast<std::size_t>(c.b1)].id,
                               b[static_cast<std::size_t>(c.b2)].id);
        }
    };
    once();  // warm-up
    std::vector<double> times;
    for (int r = 0; r < runs; ++r) {
        auto s = Clock::now();
        once();
        times.push_back(ms_since(s));
    }
    std::sort(times.begin(), times.end());
    const int drop = (runs - 1) / 4;
    double sum = 0;
    for (int r = drop; r < runs - drop; ++r) {
        sum += times[r];
    }
    const double collide_ms = sum / (runs - 2 * drop);
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    std::string path = out + "-" + name + ".pairs";
    std::ofstream f(path, std::ios::binary);
    for (const auto &p : pairs) {
        f.write(reinterpret_cast<const char *>(&p.first), 4);
        f.write(reinterpret_cast<const char *>(&p.second), 4);
    }
    std::printf("fcl-%s build_ms %.3f collide_ms %.4f pairs %zu\n", name, build_ms, collide_ms,
                pairs.size());
}

}  // namespace

int main(int argc, char **argv) {
    if (argc != 5) {
        std::fprintf(stderr, "usage: %s A.tris B.tris RUNS OUT\n", argv[0]);
        return 2;
    }
    const int runs = std::atoi(argv[3]);
    if (runs < 1 || runs > 1000) {
        std::fprintf(stderr, "fcl_collide: RUNS must be 1..1000\n");
        return 2;
    }
    const auto a = read_tris(argv[1]);
    const auto b = read_tris(argv[2]);
    run<fcl::OBBRSSd>("obbrss", a, b, runs, argv[4]);
    run<fcl::AABBd>("aabb", a, b, runs, argv[4]);
    return 0;
}
