/* DEM test helpers (see dem_test_util.h). */
#include "dem_test_util.h"
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"

int dem_test_failures = 0;

void dem_test_check(int ok, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("%s: ", ok ? "ok  " : "FAIL");
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
    if (!ok) dem_test_failures++;
    fflush(stdout);
}

void dem_test_rel(const char *what, double value, double ref, double tol)
{
    double rel = fabs(value - ref) / fabs(ref);
    dem_test_check(rel <= tol, "%s = %.8g, reference %.8g, relative error %.3e (tolerance %.1e)", what, value, ref,
                   rel, tol);
}

void dem_test_abs(const char *what, double value, double ref, double tol)
{
    double d = fabs(value - ref);
    dem_test_check(d <= tol, "%s = %.8g, reference %.8g, error %.3e (tolerance %.1e)", what, value, ref, d, tol);
}

void dem_test_case_init(lahar_case *c, int dim, const double g[3], int cap)
{
    memset(c, 0, sizeof *c);
    c->dim = dim;
    memcpy(c->gravity, g, sizeof c->gravity);
    c->t_end = 1.0;
    c->dt_max = 1e-3;
    c->dt_min = 1e-12;
    snprintf(c->dem_engine, sizeof c->dem_engine, "spheropoly");
    c->dem_dt_safety = 0.02;
    c->materials = calloc(8, sizeof(lahar_material));
    c->bodies = calloc((size_t)cap, sizeof(lahar_body));
    if (!c->materials || !c->bodies) {
        fprintf(stderr, "out of memory\n");
        exit(2);
    }
}

void dem_test_case_free(lahar_case *c)
{
    for (int i = 0; i < c->nbody; i++) lahar_shape_free(&c->bodies[i].shape);
    free(c->bodies);
    free(c->materials);
    memset(c, 0, sizeof *c);
}

int dem_test_material(lahar_case *c, const char *name, lahar_contact_model model, double density, double kn,
                      double young, double poisson, double restitution, double friction)
{
    lahar_material *m = &c->materials[c->nmaterial];
    memset(m, 0, sizeof *m);
    snprintf(m->name, sizeof m->name, "%s", name);
    m->model = model;
    m->density = density;
    m->kn = kn;
    m->young = young;
    m->poisson = poisson;
    m->kt_ratio = 2.0 / 7.0;
    m->restitution = restitution;
    m->friction = friction;
    return c->nmaterial++;
}

static lahar_body *new_body(lahar_case *c, const char *name, int mat, lahar_motion motion)
{
    lahar_body *b = &c->bodies[c->nbody++];
    memset(b, 0, sizeof *b);
    snprintf(b->name, sizeof b->name, "%s", name);
    b->material = mat;
    b->motion = motion;
    b->convex = 1;
    b->q[0] = 1.0;
    return b;
}

static void need(int ok, const char *what)
{
    if (!ok) {
        fprintf(stderr, "dem_test_util: %s failed\n", what);
        exit(2);
    }
}

int dem_test_sphere(lahar_case *c, const char *name, int mat, double radius, const double x[3], lahar_motion motion)
{
    lahar_body *b = new_body(c, name, mat, motion);
    need(lahar_shape_make_sphere(&b->shape, radius) == 0, "make_sphere");
    double rho = c->materials[mat].density;
    if (c->dim == 2) {
        b->mass = M_PI * radius * radius * rho;
        b->inertia[0] = b->inertia[1] = 0.25 * b->mass * radius * radius; /* unused in 2D */
        b->inertia[2] = 0.5 * b->mass * radius * radius;
    } else {
        b->mass = 4.0 / 3.0 * M_PI * radius * radius * radius * rho;
        b->inertia[0] = b->inertia[1] = b->inertia[2] = 0.4 * b->mass * radius * radius;
    }
    memcpy(b->x, x, sizeof b->x);
    return c->nbody - 1;
}

int dem_test_box(lahar_case *c, const char *name, int mat, const double half[3], double r, const double x[3],
                 const double q[4], lahar_motion motion)
{
    lahar_body *b = new_body(c, name, mat, motion);
    char err[256];
    lahar_mass_props mp;
    if (c->dim == 2) need(lahar_shape_make_box2d(&b->shape, half, r) == 0, "make_box2d");
    else need(lahar_shape_make_box(&b->shape, half, r) == 0, "make_box");
    need(lahar_shape_mass_properties(&b->shape, c->dim, &mp, err, sizeof err) == 0, "mass_properties");
    double rho = c->materials[mat].density;
    b->mass = mp.volume * rho;
    for (int k = 0; k < 3; k++) b->inertia[k] = mp.inertia[k] * rho;
    memcpy(b->x, x, sizeof b->x);
    if (q) memcpy(b->q, q, sizeof b->q);
    return c->nbody - 1;
}

int dem_test_plane(lahar_case *c, const char *name, int mat, const double centre[3], const double n[3],
                   const double size[2], double r)
{
    lahar_body *b = new_body(c, name, mat, LAHAR_MOTION_FIXED);
    need(lahar_shape_make_plane(&b->shape, centre, n, size, r) == 0, "make_plane");
    return c->nbody - 1;
}

int dem_test_segment(lahar_case *c, const char *name, int mat, const double a[3], const double b3[3], double r)
{
    lahar_body *b = new_body(c, name, mat, LAHAR_MOTION_FIXED);
    need(lahar_shape_make_segment(&b->shape, a, b3, r) == 0, "make_segment");
    return c->nbody - 1;
}

lahar_dem_engine *dem_test_engine(const lahar_case *c, const lahar_dem_engine_ops **ops)
{
    char err[512] = "";
    *ops = lahar_dem_engine_find("spheropoly");
    need(*ops != NULL, "lahar_dem_engine_find(spheropoly)");
    lahar_dem_engine *e = (*ops)->create(c, err, sizeof err);
    if (!e) {
        fprintf(stderr, "create: %s\n", err);
        exit(2);
    }
    return e;
}

unsigned long long dem_test_digest(const lahar_dem_engine_ops *ops, const lahar_dem_engine *e)
{
    unsigned long long h = 1469598103934665603ull;
    for (int i = 0; i < ops->nbody(e); i++) {
        lahar_body_state st;
        ops->get_state(e, i, &st);
        const unsigned char *p = (const unsigned char *)&st;
        for (size_t k = 0; k < sizeof st; k++) h = (h ^ p[k]) * 1099511628211ull;
    }
    return h;
}
