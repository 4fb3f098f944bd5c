/* rim_split.h — an open mesh's rim sampled twice as densely: each free
 * edge split at its midpoint m, its facet cut in two along the chord
 * from m to its middle vertex (a facet with more than one free edge
 * keeps m uncut), planes kept. The halves of one cut with one of them
 * split so meet on one polyline sampled differently (stitch.h, 5a). */
#ifndef TEST_RIM_SPLIT_H
#define TEST_RIM_SPLIT_H

#include "poly.h"

/* The new mesh (the caller frees it); facets of up to 254 corners. */
geo_poly *rim_split(const geo_poly *p);

#endif
