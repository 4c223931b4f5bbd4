/* Fixed box walls for the library-level tests that build their scene in C (the cases make theirs
 * from `shape: box`, common/scene). A box is a sphero-polyhedron: an inner box of half-size
 * outer_half - radius swept by the radius, so its outer surface lies at centre +- outer_half. */
#ifndef LAHAR_TEST_BODIES_H
#define LAHAR_TEST_BODIES_H
#include "scene.h"

/* A fixed, convex box body at rest: dim 2 (a rectangle in the z = 0 plane; centre[2] and
 * outer_half[2] unused) or 3. Aborts when the shape cannot be made. */
void test_fixed_box(lahar_body *b, int dim, const double centre[3], const double outer_half[3], double radius);
/* The same in 2D from the centre (cx, cy) and the outer half-sizes (hx, hy). */
void test_fixed_box2d(lahar_body *b, double cx, double cy, double hx, double hy, double radius);
/* The same from the outer box's corners [lo, hi]. */
void test_fixed_box_lohi(lahar_body *b, int dim, const double lo[3], const double hi[3], double radius);

#endif
