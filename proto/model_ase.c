/* model_ase.c — ASE (3ds Max ASCII Scene Export), write only: the export
 * format of Vyatkin's triangulation program. One GEOMOBJECT holds the
 * model as a triangle mesh: *MESH_VERTEX_LIST with every vertex,
 * *MESH_FACE_LIST with every facet split into triangles
 * (lib/core/polygon_triangulate.h), AB/BC/CA marking which triangle edges are
 * edges of the original facet (1) and which are diagonals added by the
 * split (0), and *MESH_NORMALS with each triangle's facet normal (flat
 * shading: the vertex normals of a triangle are its facet's). Numbers are
 * the shortest decimals that read back exactly. */
#include "model_codec.h"

static int polygon_edge(uint32_t a, uint32_t b, uint32_t n)
{
    return (a + 1) % n == b || (b + 1) % n == a;
}

static void put_xyz(proto_buf *b, const double *v)
{
    for (int k = 0; k < 3; k++) {
        proto_buf_puts(b, "\t");
        proto_buf_double(b, v[k]);
    }
    proto_buf_puts(b, "\n");
}

/* One pass over the triangles: pass 0 the faces, pass 1 the normals;
 * t numbers the triangles. */
typedef struct ase_pass {
    proto_buf *b;
    int pass;
    uint64_t t;
} ase_pass;

static void emit_triangle(const geo_poly *p, uint32_t f, const uint32_t *q,
                          void *arg)
{
    ase_pass *a = arg;
    proto_buf *b = a->b;
    uint32_t n = geo_poly_facet_size(p, f);
    const uint32_t *v = geo_poly_facet(p, f);
    unsigned long long t = a->t++;
    if (a->pass == 0) {
        proto_buf_printf(b,
                         "\t\t\t*MESH_FACE %llu:\tA: %u\tB: %u\tC: %u\t"
                         "AB: %d\tBC: %d\tCA: %d\t*MESH_SMOOTHING 0\t"
                         "*MESH_MTLID 0\n",
                         t, v[q[0]], v[q[1]], v[q[2]],
                         polygon_edge(q[0], q[1], n),
                         polygon_edge(q[1], q[2], n),
                         polygon_edge(q[2], q[0], n));
        return;
    }
    proto_buf_printf(b, "\t\t\t*MESH_FACENORMAL %llu", t);
    put_xyz(b, p->planes[f]);
    for (int c = 0; c < 3; c++) {
        proto_buf_printf(b, "\t\t\t\t*MESH_VERTEXNORMAL %u", v[q[c]]);
        put_xyz(b, p->planes[f]);
    }
}

int proto_ase_write(const geo_poly *p, proto_buf *b, geo_err *err)
{
    uint64_t nt = geo_poly_ncorners(p) - 2 * (uint64_t)p->nfacets;
    proto_buf_puts(b, "*3DSMAX_ASCIIEXPORT\t200\n"
                      "*COMMENT \"facetd: polyhedron in millimetres\"\n"
                      "*SCENE {\n"
                      "\t*SCENE_FILENAME \"\"\n"
                      "\t*SCENE_FIRSTFRAME 0\n"
                      "\t*SCENE_LASTFRAME 0\n"
                      "\t*SCENE_FRAMESPEED 30\n"
                      "\t*SCENE_TICKSPERFRAME 160\n"
                      "}\n"
                      "*GEOMOBJECT {\n"
                      "\t*NODE_NAME \"model\"\n"
                      "\t*NODE_TM {\n"
                      "\t\t*NODE_NAME \"model\"\n"
                      "\t\t*TM_ROW0 1\t0\t0\n"
                      "\t\t*TM_ROW1 0\t1\t0\n"
                      "\t\t*TM_ROW2 0\t0\t1\n"
                      "\t\t*TM_ROW3 0\t0\t0\n"
                      "\t}\n"
                      "\t*MESH {\n"
                      "\t\t*TIMEVALUE 0\n");
    proto_buf_printf(b, "\t\t*MESH_NUMVERTEX %u\n\t\t*MESH_NUMFACES %llu\n"
                        "\t\t*MESH_VERTEX_LIST {\n",
                     p->nverts, (unsigned long long)nt);
    for (uint32_t i = 0; i < p->nverts; i++) {
        proto_buf_printf(b, "\t\t\t*MESH_VERTEX %u", i);
        put_xyz(b, p->verts[i]);
    }
    proto_buf_puts(b, "\t\t}\n\t\t*MESH_FACE_LIST {\n");
    /* the triangles twice: faces first, then normals, as ASE orders them */
    for (int pass = 0; pass < 2; pass++) {
        ase_pass a = {b, pass, 0};
        int e = proto_each_triangle(p, emit_triangle, &a, err);
        if (e < 0)
            return e;
        proto_buf_puts(b, pass == 0 ? "\t\t}\n\t\t*MESH_NUMTVERTEX 0\n"
                                      "\t\t*MESH_NORMALS {\n"
                                    : "\t\t}\n\t}\n}\n");
    }
    return 0;
}
