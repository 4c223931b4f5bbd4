/* Fixed box walls for the library-level tests (test_bodies.h). */
#include "test_bodies.h"
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"

void test_fixed_box(lahar_body *b, int dim, const double centre[3], const double outer_half[3], double radius)
{
    memset(b, 0, sizeof *b);
    double half[3] = {0.0, 0.0, 0.0}, t[3] = {centre[0], centre[1], dim == 3 ? centre[2] : 0.0};
    for (int a = 0; a < dim; a++)
        half[a] = outer_half[a] - radius;
    if ((dim == 2 ? lahar_shape_make_box2d(&b->shape, half, radius) : lahar_shape_make_box(&b->shape, half, radius)) != 0)
        abort();
    lahar_shape_transform(&b->shape, NULL, t, 1.0);
    b->motion = LAHAR_MOTION_FIXED;
    b->convex = 1;
    b->q[0] = 1.0;
}

void test_fixed_box2d(lahar_body *b, double cx, double cy, double hx, double hy, double radius)
{
    const double centre[3] = {cx, cy, 0.0}, outer_half[3] = {hx, hy, 0.0};
    test_fixed_box(b, 2, centre, outer_half, radius);
}

void test_fixed_box_lohi(lahar_body *b, int dim, const double lo[3], const double hi[3], double radius)
{
    double centre[3] = {0.0, 0.0, 0.0}, outer_half[3] = {0.0, 0.0, 0.0};
    for (int a = 0; a < dim; a++) {
        outer_half[a] = 0.5 * (hi[a] - lo[a]);
        centre[a] = 0.5 * (hi[a] + lo[a]);
    }
    test_fixed_box(b, dim, centre, outer_half, radius);
}
