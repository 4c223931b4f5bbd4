/* Building lahar_case structs directly in C for the DEM tests: materials, spheres/discs, boxes,
 * planes and segment walls with their mass properties. Shapes come from common/geometry/shape_build. */
#ifndef LAHAR_DEM_TEST_UTIL_H
#define LAHAR_DEM_TEST_UTIL_H
#include "dem_engine.h"
#include "scene.h"

/* Empty case of dimension dim with gravity g; room for up to cap bodies and 8 materials.
 * dem_dt_safety 0.02, dt_max 1e-3 (the step used when nothing can touch). */
void dem_test_case_init(lahar_case *c, int dim, const double g[3], int cap);
void dem_test_case_free(lahar_case *c);

/* Material; returns its index. Linear uses kn, Hertz uses young/poisson. kt_ratio 2/7. */
int dem_test_material(lahar_case *c, const char *name, lahar_contact_model model, double density, double kn,
                      double young, double poisson, double restitution, double friction);

/* Sphere (3D: m = 4/3 pi R^3 rho, I = 2/5 m R^2) or disc (2D, per unit thickness: m = pi R^2 rho,
 * I = 1/2 m R^2). Returns the body index. */
int dem_test_sphere(lahar_case *c, const char *name, int mat, double radius, const double x[3], lahar_motion motion);
/* Box with core half-extents half and sweep radius r (exact rounded-box mass properties from
 * lahar_shape_mass_properties, the box being symmetric its principal axes are the box axes),
 * orientation q (w, x, y, z). */
int dem_test_box(lahar_case *c, const char *name, int mat, const double half[3], double r, const double x[3],
                 const double q[4], lahar_motion motion);
/* Fixed one-sided rectangle (centre, outward normal, side lengths), world-frame geometry. */
int dem_test_plane(lahar_case *c, const char *name, int mat, const double centre[3], const double n[3],
                   const double size[2], double r);
/* Fixed segment wall a-b (2D ground), world-frame geometry. */
int dem_test_segment(lahar_case *c, const char *name, int mat, const double a[3], const double b[3], double r);

/* The spheropoly engine for case c; aborts the test with a message on failure. */
lahar_dem_engine *dem_test_engine(const lahar_case *c, const lahar_dem_engine_ops **ops);
/* FNV-1a over every body state (get_state): equal digests = bitwise equal runs (threads, optimisations). */
unsigned long long dem_test_digest(const lahar_dem_engine_ops *ops, const lahar_dem_engine *e);

/* Test bookkeeping: prints "ok"/"FAIL" lines, counts failures. */
extern int dem_test_failures;
void dem_test_check(int ok, const char *fmt, ...);
/* |value - ref| <= tol * |ref| (relative) */
void dem_test_rel(const char *what, double value, double ref, double tol);
/* |value - ref| <= tol (absolute) */
void dem_test_abs(const char *what, double value, double ref, double tol);

#endif
