// cgal_selfint.cpp — CGAL's self-intersection test, in-process, for the
// side-by-side inspection benchmark (tests/bench/inspect_vs_cgal.sh).
//
//   cgal_selfint MODEL.obj|.off|.ply [RUNS]
//
// Reads the mesh into a Surface_mesh (Epick, as CGAL's own examples do),
// triangulates polygonal faces (the test requires a triangle mesh; a gem
// scan's facets are polygons), then times PMP::does_self_intersect alone — the mesh already built, the
// reading not counted — RUNS times (default 1) and prints
// "cgal_selfint_ms: BEST cpu_ms: CPU self_intersect: 0|1 triangles: N"
// (BEST the best wall time, CPU the processor time of that run). Exit 0,
// 1 when the file cannot be read.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_faces.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Surface_mesh<K::Point_3> Mesh;
namespace PMP = CGAL::Polygon_mesh_processing;

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 3) {
        std::fprintf(stderr, "usage: cgal_selfint MODEL.obj|.off|.ply [RUNS]\n");
        return 2;
    }
    int runs = argc == 3 ? std::atoi(argv[2]) : 1;
    if (runs < 1)
        runs = 1;
    Mesh m;
    if (!PMP::IO::read_polygon_mesh(argv[1], m) || m.is_empty()) {
        std::fprintf(stderr, "cgal_selfint: %s: cannot read a mesh\n", argv[1]);
        return 1;
    }
    if (!CGAL::is_triangle_mesh(m))
        PMP::triangulate_faces(m);
    double best = 1e30, best_cpu = 0;
    bool si = false;
    for (int r = 0; r < runs; r++) {
        std::clock_t c0 = std::clock();
        auto t0 = std::chrono::steady_clock::now();
        si = PMP::does_self_intersect<CGAL::Sequential_tag>(m);
        auto t1 = std::chrono::steady_clock::now();
        std::clock_t c1 = std::clock();
        double ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
        if (ms < best) {
            best = ms;
            best_cpu = 1e3 * (double)(c1 - c0) / CLOCKS_PER_SEC;
        }
    }
    std::printf("cgal_selfint_ms: %.3f cpu_ms: %.3f self_intersect: %d "
                "triangles: %zu\n",
                best, best_cpu, si ? 1 : 0, (size_t)m.number_of_faces());
    return 0;
}
