/* Sphere (3D) and disc (2D) on an incline (reference 06 sec. 6.4): rolling without slip at
 * a = 5/7 g sin(theta) (disc 2/3) when mu >= 2/7 tan(theta) (disc 1/3), sliding at
 * a = g (sin(theta) - mu cos(theta)) otherwise; within 1 %. The incline is a horizontal floor
 * with gravity tilted by theta (same physics, exact geometry). The acceleration is measured from
 * the COM velocity between t = 0.2 s (after the start transient) and t = 1.2 s. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include "dem_test_util.h"
#include "shape_build.h"

/* A fixed terrain made of many small features (so the engine gives it a feature grid): 3D a
 * sheet of 2 x 60 x 8 triangles, 2D a polyline of 100 segments, both flat at height 0. */
static void add_terrain(lahar_case *c, int mat, double rp)
{
    lahar_body *b = &c->bodies[c->nbody++];
    snprintf(b->name, sizeof b->name, "terrain");
    b->material = mat;
    b->motion = LAHAR_MOTION_FIXED;
    b->q[0] = 1.0;
    char err[256];
    int rc;
    if (c->dim == 3) {
        enum { NX = 60, NY = 8 };
        static double v[(NX + 1) * (NY + 1)][3];
        static int fs[2 * NX * NY + 1], fv[6 * NX * NY];
        for (int j = 0; j <= NY; j++)
            for (int i = 0; i <= NX; i++) {
                v[j * (NX + 1) + i][0] = -1.0 + 10.0 * i / NX;
                v[j * (NX + 1) + i][1] = -0.4 + 0.8 * j / NY;
                v[j * (NX + 1) + i][2] = 0.0;
            }
        int nf = 0;
        for (int j = 0; j < NY; j++)
            for (int i = 0; i < NX; i++) {
                int a = j * (NX + 1) + i, bb = a + 1, cc = a + NX + 2, d = a + NX + 1;
                int tri[2][3] = {{a, bb, cc}, {a, cc, d}}; /* counter-clockwise seen from +z */
                for (int t = 0; t < 2; t++) {
                    fs[nf] = 3 * nf;
                    for (int k = 0; k < 3; k++) fv[3 * nf + k] = tri[t][k];
                    nf++;
                }
            }
        fs[nf] = 3 * nf;
        rc = lahar_shape_make_polyhedron(&b->shape, (const double(*)[3])v, (NX + 1) * (NY + 1), fs, fv, nf, rp, err,
                                         sizeof err);
    } else {
        static double p[101][3];
        for (int i = 0; i <= 100; i++) {
            p[i][0] = -1.0 + 10.0 * i / 100;
            p[i][1] = p[i][2] = 0.0;
        }
        rc = lahar_shape_make_polyline(&b->shape, (const double(*)[3])p, 101, 0, rp, err, sizeof err);
    }
    if (rc) {
        fprintf(stderr, "terrain: %s\n", err);
        exit(2);
    }
}

static double incline_accel_on(int dim, double theta, double mu, double *spin_ratio, int terrain, double y0)
{
    const double g = 9.81, R = 0.05, rp = 0.01, kn = 1e6;
    double gv[3] = {g * sin(theta), 0, 0};
    gv[dim == 3 ? 2 : 1] = -g * cos(theta);
    lahar_case c;
    dem_test_case_init(&c, dim, gv, 2);
    int m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, kn, 0, 0, 0.5, mu);
    if (terrain) {
        add_terrain(&c, m, rp);
    } else if (dim == 3) {
        const double centre[3] = {4, 0, 0}, n[3] = {0, 0, 1}, size[2] = {10, 2};
        dem_test_plane(&c, "slope", m, centre, n, size, rp);
    } else {
        const double a[3] = {-1, 0, 0}, b[3] = {9, 0, 0};
        dem_test_segment(&c, "slope", m, a, b, rp);
    }
    double x[3] = {0, y0, 0};
    int s = dem_test_sphere(&c, "ball", m, R, x, LAHAR_MOTION_FREE);
    /* start at the static overlap so that the normal transient is small */
    c.bodies[s].x[dim == 3 ? 2 : 1] = R + rp - c.bodies[s].mass * g * cos(theta) / kn;
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    const double dt = 1e-3, t1 = 0.2, t2 = 1.2;
    double v1 = 0.0, v2 = 0.0, w2 = 0.0;
    char err[512];
    for (int k = 1; k <= (int)lround(t2 / dt); k++) {
        if (ops->advance(e, dt, NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        lahar_body_state st;
        ops->get_state(e, s, &st);
        if (k == (int)lround(t1 / dt)) v1 = st.v[0];
        if (k == (int)lround(t2 / dt)) {
            v2 = st.v[0];
            w2 = dim == 3 ? st.w[1] : -st.w[2];
        }
    }
    *spin_ratio = w2 * R / v2; /* 1 when rolling without slip */
    ops->destroy(e);
    dem_test_case_free(&c);
    return (v2 - v1) / (t2 - t1);
}

static double incline_accel(int dim, double theta, double mu, double *spin_ratio)
{
    return incline_accel_on(dim, theta, mu, spin_ratio, 0, 0.0371);
}

/* The same with a really tilted plane (normal (-sin, 0, cos)) and vertical gravity: the
 * acceleration along the slope, from the velocity component along it. */
static double tilted_plane_accel(double theta, double mu)
{
    const double g = 9.81, R = 0.05, rp = 0.01, kn = 1e6;
    const double gv[3] = {0, 0, -g};
    lahar_case c;
    dem_test_case_init(&c, 3, gv, 2);
    int m = dem_test_material(&c, "rock", LAHAR_CONTACT_LINEAR, 2500.0, kn, 0, 0, 0.5, mu);
    const double n[3] = {-sin(theta), 0, cos(theta)}, centre[3] = {0, 0, 0}, size[2] = {12, 2};
    dem_test_plane(&c, "slope", m, centre, n, size, rp);
    double up[3] = {cos(theta), 0, sin(theta)}; /* up the slope (the surface rises along +x) */
    double x[3];
    int s = dem_test_sphere(&c, "ball", m, R, up, LAHAR_MOTION_FREE);
    double hgt = R + rp - c.bodies[s].mass * g * cos(theta) / kn;
    for (int k = 0; k < 3; k++) x[k] = 2.0 * up[k] + hgt * n[k];
    for (int k = 0; k < 3; k++) c.bodies[s].x[k] = x[k];
    const lahar_dem_engine_ops *ops;
    lahar_dem_engine *e = dem_test_engine(&c, &ops);
    char err[512];
    double v1 = 0.0, v2 = 0.0;
    for (int k = 1; k <= 1200; k++) {
        if (ops->advance(e, 1e-3, NULL, err, sizeof err) < 0) {
            dem_test_check(0, "advance: %s", err);
            break;
        }
        lahar_body_state st;
        ops->get_state(e, s, &st);
        double vs = -(st.v[0] * up[0] + st.v[1] * up[1] + st.v[2] * up[2]);
        if (k == 200) v1 = vs;
        if (k == 1200) v2 = vs;
    }
    ops->destroy(e);
    dem_test_case_free(&c);
    return (v2 - v1) / 1.0;
}

int main(void)
{
    const double g = 9.81, th = 30.0 * M_PI / 180.0;
    double spin;
    /* sphere: threshold mu = 2/7 tan 30 = 0.165 */
    double a = incline_accel(3, th, 0.5, &spin);
    dem_test_rel("sphere rolling (mu 0.5) acceleration vs 5/7 g sin", a, 5.0 / 7.0 * g * sin(th), 0.01);
    dem_test_rel("sphere rolling: w R / v", spin, 1.0, 0.01);
    a = incline_accel(3, th, 0.1, &spin);
    dem_test_rel("sphere sliding (mu 0.1) acceleration vs g (sin - mu cos)", a, g * (sin(th) - 0.1 * cos(th)), 0.01);
    dem_test_check(spin < 0.9, "sphere sliding: w R / v = %.3f < 1 (slips)", spin);
    /* disc: threshold mu = 1/3 tan 30 = 0.192 */
    a = incline_accel(2, th, 0.5, &spin);
    dem_test_rel("disc rolling (mu 0.5) acceleration vs 2/3 g sin", a, 2.0 / 3.0 * g * sin(th), 0.01);
    dem_test_rel("disc rolling: w R / v", spin, 1.0, 0.01);
    a = incline_accel(2, th, 0.1, &spin);
    dem_test_rel("disc sliding (mu 0.1) acceleration vs g (sin - mu cos)", a, g * (sin(th) - 0.1 * cos(th)), 0.01);
    dem_test_check(spin < 0.9, "disc sliding: w R / v = %.3f < 1 (slips)", spin);
    a = tilted_plane_accel(th, 0.5);
    dem_test_rel("sphere rolling on a tilted plane vs 5/7 g sin", a, 5.0 / 7.0 * g * sin(th), 0.01);
    a = tilted_plane_accel(th, 0.1);
    dem_test_rel("sphere sliding on a tilted plane vs g (sin - mu cos)", a, g * (sin(th) - 0.1 * cos(th)), 0.01);
    /* the same on a fine terrain mesh (feature grid; contacts move across triangles/segments and
     * keep their tangential spring, so the motion equals the one on a single plane) */
    double a_plane = incline_accel(3, th, 0.5, &spin);
    a = incline_accel_on(3, th, 0.5, &spin, 1, 0.0371); /* off the mesh lines */
    dem_test_rel("sphere rolling on a 960-triangle terrain vs 5/7 g sin", a, 5.0 / 7.0 * g * sin(th), 0.01);
    dem_test_rel("sphere rolling on the terrain vs on a single plane", a, a_plane, 1e-6);
    a = incline_accel_on(3, th, 0.1, &spin, 1, 0.0371);
    dem_test_rel("sphere sliding on a 960-triangle terrain vs g (sin - mu cos)", a, g * (sin(th) - 0.1 * cos(th)), 0.01);
    /* along a grid line of the mesh (y = 0): the contact point sits on shared edges and vertices */
    a = incline_accel_on(3, th, 0.5, &spin, 1, 0.0);
    dem_test_rel("sphere rolling along a mesh line vs on a single plane", a, a_plane, 1e-6);
    a_plane = incline_accel(2, th, 0.5, &spin);
    a = incline_accel_on(2, th, 0.5, &spin, 1, 0.0);
    dem_test_rel("disc rolling on a 100-segment polyline vs 2/3 g sin", a, 2.0 / 3.0 * g * sin(th), 0.01);
    dem_test_rel("disc rolling on the polyline vs on a single segment", a, a_plane, 1e-6);
    return dem_test_failures ? 1 : 0;
}
