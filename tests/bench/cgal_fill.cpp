// cgal_fill.cpp — the reference side of the hole-filling benchmark: CGAL
// 5.5's PMP::triangulate_refine_and_fair_hole on every hole of each OFF
// file given, timed around the call alone (reading and writing excluded),
// so tests/bench/fill_cgal.sh can print it beside `facet fill` on the
// same holes. Prints one JSON line per file: boundary vertices of its
// holes, milliseconds, faces and vertices added, and whether the patches
// added self-intersections (PMP::does_self_intersect on the result).
// Usage: cgal_fill FILE.off...
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/border.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>

#include <chrono>
#include <cstdio>
#include <iterator>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef CGAL::Surface_mesh<K::Point_3> Mesh;
typedef boost::graph_traits<Mesh>::halfedge_descriptor halfedge;
typedef boost::graph_traits<Mesh>::face_descriptor face;
typedef boost::graph_traits<Mesh>::vertex_descriptor vertex;
namespace PMP = CGAL::Polygon_mesh_processing;

int main(int argc, char **argv)
{
    int status = 0;
    for (int a = 1; a < argc; a++) {
        Mesh m;
        if (!PMP::IO::read_polygon_mesh(argv[a], m) || m.is_empty()) {
            std::fprintf(stderr, "cgal_fill: %s: cannot read\n", argv[a]);
            status = 1;
            continue;
        }
        std::vector<halfedge> borders;
        PMP::extract_boundary_cycles(m, std::back_inserter(borders));
        size_t nfaces0 = m.number_of_faces(), nverts0 = m.number_of_vertices();
        long boundary = 0, filled = 0;
        double ms = 0;
        for (halfedge h : borders) {
            long n = 0;
            for (halfedge x : CGAL::halfedges_around_face(h, m)) {
                (void)x;
                n++;
            }
            boundary += n;
            std::vector<face> nf;
            std::vector<vertex> nv;
            auto t0 = std::chrono::steady_clock::now();
            bool ok = std::get<0>(PMP::triangulate_refine_and_fair_hole(
                m, h, std::back_inserter(nf), std::back_inserter(nv)));
            auto t1 = std::chrono::steady_clock::now();
            ms += std::chrono::duration<double, std::milli>(t1 - t0).count();
            filled += ok;
        }
        bool si = PMP::does_self_intersect(m);
        std::printf("{\"file\":\"%s\",\"holes\":%zu,\"filled\":%ld,"
                    "\"boundary\":%ld,\"ms\":%.1f,\"faces_added\":%zu,"
                    "\"vertices_added\":%zu,\"self_intersecting\":%s}\n",
                    argv[a], borders.size(), filled, boundary, ms,
                    m.number_of_faces() - nfaces0,
                    m.number_of_vertices() - nverts0, si ? "true" : "false");
    }
    return status;
}
