/* rigid.c — rigid motions of rigid.h (Rodrigues' rotation matrix). */
#include "rigid.h"

#include <math.h>
#include <string.h>

void tu_rigid_move(geo_poly *p, const double axis[3], double deg,
                   const double t[3])
{
    double l = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double k[3] = {axis[0] / l, axis[1] / l, axis[2] / l};
    double a = deg * M_PI / 180.0;
    double s = sin(a), c = cos(a), v = 1 - c, R[3][3] = {
        {c + k[0] * k[0] * v, k[0] * k[1] * v - k[2] * s,
         k[0] * k[2] * v + k[1] * s},
        {k[1] * k[0] * v + k[2] * s, c + k[1] * k[1] * v,
         k[1] * k[2] * v - k[0] * s},
        {k[2] * k[0] * v - k[1] * s, k[2] * k[1] * v + k[0] * s,
         c + k[2] * k[2] * v}};
    for (uint32_t i = 0; i < p->nverts; i++) {
        double x[3];
        for (int r = 0; r < 3; r++)
            x[r] = R[r][0] * p->verts[i][0] + R[r][1] * p->verts[i][1] +
                   R[r][2] * p->verts[i][2] + t[r];
        memcpy(p->verts[i], x, sizeof x);
    }
    for (uint32_t f = 0; f < p->nfacets; f++) {
        double n[3], *q = p->planes[f];
        for (int r = 0; r < 3; r++)
            n[r] = R[r][0] * q[0] + R[r][1] * q[1] + R[r][2] * q[2];
        q[3] -= n[0] * t[0] + n[1] * t[1] + n[2] * t[2];
        memcpy(q, n, sizeof n);
    }
}
