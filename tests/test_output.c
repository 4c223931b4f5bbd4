/* Output writers with synthetic data: display meshes against exact areas/volumes, bodies.h5
 * header/geometry/snapshots reread with HDF5, the force stream (every step and at an interval),
 * particle SoA snapshots, and the XDMF sidecars (their XML and dataset references are checked
 * by tests/test_output_xdmf.py on the directory this program leaves behind).
 *   test_output OUTDIR */
#include <hdf5.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#include "output.h"
#include "shape_build.h"
#include "vec.h"

#include "test_util.h"

static int close_rel(double a, double b, double tol) { return fabs(a - b) <= tol * fmax(fabs(a), fabs(b)) + 1e-300; }

/* Every directed edge of a triangle mesh appears once and its reverse once: closed, consistently
 * oriented surface. */
static int mesh_closed(const lahar_display_mesh *m)
{
    for (int k = 0; k < m->ncell; k++)
        for (int j = 0; j < 3; j++) {
            int a = m->cell[3 * k + j], b = m->cell[3 * k + (j + 1) % 3], same = 0, rev = 0;
            for (int l = 0; l < m->ncell; l++)
                for (int i = 0; i < 3; i++) {
                    int c = m->cell[3 * l + i], d = m->cell[3 * l + (i + 1) % 3];
                    same += c == a && d == b;
                    rev += c == b && d == a;
                }
            if (same != 1 || rev != 1)
                return 0;
        }
    return 1;
}

static double mesh_volume(const lahar_display_mesh *m)
{
    double v = 0.0;
    for (int k = 0; k < m->ncell; k++) {
        vec3 p0 = v3_load(m->v[m->cell[3 * k]]), p1 = v3_load(m->v[m->cell[3 * k + 1]]),
             p2 = v3_load(m->v[m->cell[3 * k + 2]]);
        v += v3_dot(p0, v3_cross(p1, p2)) / 6.0;
    }
    return v;
}

/* 2D: segments form closed loops; signed area by the shoelace formula over the segments. */
static double outline_area(const lahar_display_mesh *m)
{
    double a = 0.0;
    for (int k = 0; k < m->ncell; k++) {
        const double *p = m->v[m->cell[2 * k]], *q = m->v[m->cell[2 * k + 1]];
        a += 0.5 * (p[0] * q[1] - q[0] * p[1]);
    }
    return a;
}

static void test_meshes(void)
{
    lahar_display_mesh m;
    lahar_shape s;
    /* box core 0.4 x 0.2 x 0.1, R = 0.01: flat bevels and corner triangles give exactly
     * ABC + 2R(AB+BC+CA) + 2R^2(A+B+C) + 4R^3/3 */
    double half[3] = {0.2, 0.1, 0.05}, R = 0.01, A = 0.4, B = 0.2, C = 0.1;
    CHECK(lahar_shape_make_box(&s, half, R) == 0, "make_box");
    CHECK(lahar_display_mesh_build(&s, 3, 1, &m) == 0, "box mesh");
    double vex = A * B * C + 2 * R * (A * B + B * C + C * A) + 2 * R * R * (A + B + C) + 4.0 / 3.0 * R * R * R;
    CHECK(mesh_closed(&m), "box display mesh is not a closed oriented surface");
    CHECK(close_rel(mesh_volume(&m), vex, 1e-12), "box mesh volume %.15g vs %.15g", mesh_volume(&m), vex);
    CHECK(m.ncell == 6 * 2 + 12 * 2 + 8, "box mesh has %d triangles, expected 44", m.ncell);
    lahar_display_mesh_free(&m);
    lahar_shape_free(&s);

    /* irregular rock (hull of 20 points): closed, and its volume lies between core + R * core
     * area (offset faces only) and the exact swept volume (the flat bevels and corner fans cut
     * the rounded edges and corners) */
    {
        double pts[20][3];
        unsigned seed = 12345;
        for (int i = 0; i < 20; i++)
            for (int k = 0; k < 3; k++) {
                seed = seed * 1103515245u + 12345u;
                pts[i][k] = ((seed >> 8) % 10000) / 10000.0 * (k == 2 ? 0.06 : 0.1) - (k == 2 ? 0.03 : 0.05);
            }
        char herr[256];
        CHECK(lahar_shape_make_hull(&s, (const double(*)[3])pts, 20, 0.005, herr, sizeof herr) == 0, "hull: %s", herr);
        CHECK(lahar_display_mesh_build(&s, 3, 1, &m) == 0, "rock mesh");
        CHECK(mesh_closed(&m), "rock display mesh is not a closed oriented surface");
        double area = 0.0;
        for (int f = 0; f < s.nf; f++) {
            vec3 nw = v3(0, 0, 0);
            int f0 = s.face_start[f], k = s.face_start[f + 1] - f0;
            for (int i = 0; i < k; i++)
                nw = v3_add(nw, v3_cross(v3_load(s.v[s.face_v[f0 + i]]), v3_load(s.v[s.face_v[f0 + (i + 1) % k]])));
            area += 0.5 * v3_norm(nw);
        }
        lahar_mass_props mp;
        CHECK(lahar_shape_mass_properties(&s, 3, &mp, herr, sizeof herr) == 0, "mass props: %s", herr);
        double lo = lahar_shape_core_volume(&s) + 0.005 * area, vm = mesh_volume(&m);
        CHECK(vm > lo && vm < mp.volume, "rock mesh volume %.9g not in (%.9g, %.9g)", vm, lo, mp.volume);
        lahar_display_mesh_free(&m);
        lahar_shape_free(&s);
    }

    /* sphere: icosphere on the radius, closed, volume just under 4/3 pi R^3 */
    CHECK(lahar_shape_make_sphere(&s, 0.05) == 0, "make_sphere");
    CHECK(lahar_display_mesh_build(&s, 3, 1, &m) == 0, "sphere mesh");
    CHECK(mesh_closed(&m), "sphere mesh not closed");
    double maxdev = 0.0;
    for (int i = 0; i < m.nvert; i++)
        maxdev = fmax(maxdev, fabs(v3_norm(v3_load(m.v[i])) - 0.05));
    CHECK(maxdev < 1e-15, "icosphere vertex off the sphere by %g", maxdev);
    double ratio = mesh_volume(&m) / (4.0 / 3.0 * M_PI * 0.05 * 0.05 * 0.05);
    CHECK(ratio > 0.95 && ratio < 1.0, "icosphere volume ratio %g", ratio);
    lahar_display_mesh_free(&m);
    lahar_shape_free(&s);

    /* capsule (3D segment): spheres + tube, all vertices within R of the core segment */
    double a[3] = {-0.1, 0, 0}, b[3] = {0.1, 0, 0};
    CHECK(lahar_shape_make_segment(&s, a, b, 0.02) == 0, "make_segment");
    CHECK(lahar_display_mesh_build(&s, 3, 1, &m) == 0 && m.ncell > 0, "capsule mesh");
    lahar_display_mesh_free(&m);
    lahar_shape_free(&s);

    /* terrain: an open height-field surface of 2 * 100^2 triangles (fixed-body STL size) must
     * mesh in well under a second: corner walks and edge twins are looked up, not searched */
    {
        enum { G = 100 };
        double(*tv)[3] = malloc(sizeof *tv * (G + 1) * (G + 1));
        int *fs = malloc(sizeof *fs * (2 * G * G + 1)), *fv = malloc(sizeof *fv * 6 * G * G);
        for (int i = 0; i <= G; i++)
            for (int j = 0; j <= G; j++) {
                tv[i * (G + 1) + j][0] = 0.1 * i, tv[i * (G + 1) + j][1] = 0.1 * j;
                tv[i * (G + 1) + j][2] = 0.05 * sin(0.3 * i) * cos(0.2 * j);
            }
        int nf = 0;
        for (int i = 0; i < G; i++)
            for (int j = 0; j < G; j++) {
                int a = i * (G + 1) + j, b2 = a + G + 1;
                int tri[2][3] = {{a, b2, b2 + 1}, {a, b2 + 1, a + 1}};
                for (int t = 0; t < 2; t++, nf++) {
                    fs[nf] = 3 * nf;
                    memcpy(fv + 3 * nf, tri[t], sizeof tri[t]);
                }
            }
        fs[nf] = 3 * nf;
        char terr[256];
        int ok = lahar_shape_make_polyhedron(&s, (const double(*)[3])tv, (G + 1) * (G + 1), fs, fv, nf, 0.01, terr,
                                             sizeof terr) == 0;
        CHECK(ok, "terrain polyhedron: %s", terr);
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        CHECK(ok && lahar_display_mesh_build(&s, 3, 0, &m) == 0, "terrain mesh");
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double sec = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        /* faces + 2 per interior edge + the fans of the (G-1)^2 interior vertices (6 faces each) */
        int interior_edges = 3 * G * G - 2 * G;
        int expect = nf + 2 * interior_edges + 4 * (G - 1) * (G - 1);
        CHECK(m.ncell == expect, "terrain mesh has %d triangles, expected %d", m.ncell, expect);
        CHECK(sec < 1.0, "terrain mesh took %.2f s", sec);
        lahar_display_mesh_free(&m);
        lahar_shape_free(&s);
        free(tv), free(fs), free(fv);
    }

    /* 2D disc: a closed 48-gon, area 24 R^2 sin(2 pi/48) */
    CHECK(lahar_shape_make_sphere(&s, 0.1) == 0, "make disc");
    CHECK(lahar_display_mesh_build(&s, 2, 1, &m) == 0, "disc outline");
    CHECK(m.nodes_per_cell == 2 && m.ncell == 48, "disc outline has %d segments", m.ncell);
    CHECK(close_rel(outline_area(&m), 24 * 0.01 * sin(2 * M_PI / 48), 1e-12), "disc area %g", outline_area(&m));
    lahar_display_mesh_free(&m);
    lahar_shape_free(&s);

    /* 2D box core 0.4 x 0.2, R = 0.01: rounded outline, area ab + 2(a+b)R + 24 R^2 sin(pi/24) */
    double h2[2] = {0.2, 0.1};
    CHECK(lahar_shape_make_box2d(&s, h2, 0.01) == 0, "make_box2d");
    CHECK(lahar_display_mesh_build(&s, 2, 1, &m) == 0, "box2d outline");
    double aex = 0.4 * 0.2 + 2 * (0.4 + 0.2) * 0.01 + 24 * 1e-4 * sin(M_PI / 24);
    CHECK(close_rel(outline_area(&m), aex, 1e-12), "box2d outline area %.15g vs %.15g", outline_area(&m), aex);
    lahar_display_mesh_free(&m);
    lahar_shape_free(&s);

    /* 2D open polyline (terrain): a thin quad per segment, signed areas cancel to 2 R L each */
    double pl[3][3] = {{0, 0, 0}, {1, 0, 0}, {2, 1, 0}};
    char err[256];
    CHECK(lahar_shape_make_polyline(&s, pl, 3, 0, 0.005, err, sizeof err) == 0, "make_polyline: %s", err);
    CHECK(lahar_display_mesh_build(&s, 2, 0, &m) == 0 && m.ncell == 8, "polyline outline: %d segments", m.ncell);
    CHECK(close_rel(fabs(outline_area(&m)), 2 * 0.005 * (1.0 + sqrt(2.0)), 1e-12), "polyline quads area %g",
          outline_area(&m));
    lahar_display_mesh_free(&m);
    lahar_shape_free(&s);
}

/* ---------------------------------------------------------------- synthetic case -------- */

static lahar_material mats[2];
static lahar_body bodies[4];

static void make_case(lahar_case *c, int dim)
{
    memset(c, 0, sizeof *c);
    memset(mats, 0, sizeof mats);
    memset(bodies, 0, sizeof bodies);
    snprintf(c->path, sizeof c->path, "synthetic.yaml");
    c->dim = dim;
    c->gravity[dim == 2 ? 1 : 2] = -9.81;
    c->t_end = 1.0;
    c->output_interval = 0.1;
    c->output_forces = 1;
    snprintf(mats[0].name, sizeof mats[0].name, "rock");
    mats[0].density = 2650, mats[0].restitution = 0.5, mats[0].friction = 0.4, mats[0].young = 1e8;
    snprintf(mats[1].name, sizeof mats[1].name, "steel");
    mats[1].density = 7800, mats[1].restitution = 0.9, mats[1].friction = 0.2, mats[1].kn = 1e6;
    mats[1].model = LAHAR_CONTACT_LINEAR;
    c->nmaterial = 2;
    c->materials = mats;
    const char *names[4] = {"ball", "crate", "floor", "wall"};
    for (int b = 0; b < 4; b++) {
        snprintf(bodies[b].name, sizeof bodies[b].name, "%s", names[b]);
        bodies[b].q[0] = 1.0;
        bodies[b].material = b % 2;
        bodies[b].convex = 1;
    }
    if (dim == 3) {
        double half[3] = {0.1, 0.05, 0.05}, cen[3] = {0, 0, 0}, nrm[3] = {0, 0, 1}, size[2] = {2, 2};
        double wh[3] = {0.05, 1.0, 0.5};
        lahar_shape_make_sphere(&bodies[0].shape, 0.05);
        lahar_shape_make_box(&bodies[1].shape, half, 0.01);
        lahar_shape_make_plane(&bodies[2].shape, cen, nrm, size, 0.001);
        lahar_shape_make_box(&bodies[3].shape, wh, 0.001);
        bodies[3].x[0] = 1.0;
    } else {
        double h2[2] = {0.1, 0.05}, a[3] = {-1, 0, 0}, b[3] = {1, 0, 0};
        double pl[3][3] = {{1, 0, 0}, {1.5, 0.5, 0}, {2, 0.5, 0}};
        char err[256];
        lahar_shape_make_sphere(&bodies[0].shape, 0.05);
        lahar_shape_make_box2d(&bodies[1].shape, h2, 0.01);
        lahar_shape_make_segment(&bodies[2].shape, a, b, 0.001);
        lahar_shape_make_polyline(&bodies[3].shape, pl, 3, 0, 0.001, err, sizeof err);
        bodies[3].convex = 0;
    }
    bodies[0].mass = 1.0, bodies[0].inertia[0] = bodies[0].inertia[1] = bodies[0].inertia[2] = 0.001;
    bodies[1].mass = 2.0, bodies[1].inertia[0] = 0.01, bodies[1].inertia[1] = 0.02, bodies[1].inertia[2] = 0.03;
    bodies[2].motion = bodies[3].motion = LAHAR_MOTION_FIXED;
    c->nbody = 4;
    c->bodies = bodies;
}

static void free_case(void)
{
    for (int b = 0; b < 4; b++)
        lahar_shape_free(&bodies[b].shape);
}

static void state_at(int b, int k, lahar_body_state *s)
{
    memset(s, 0, sizeof *s);
    s->x[0] = 0.1 * b + 0.01 * k, s->x[1] = 0.2, s->x[2] = 1.0 - 0.05 * k;
    quat q = q_axis_angle(v3(0, 0, 1), 0.3 * k + b);
    q_store(q, s->q);
    s->v[0] = 0.1, s->v[2] = -0.5 * k;
    s->w[2] = 0.3 + b;
}

static hid_t open_ro(const char *path)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(fapl, 0, 1);
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, fapl);
    H5Pclose(fapl);
    return f;
}

/* Dimensions of dataset `name` (rank returned, dims filled). */
static int ds_dims(hid_t f, const char *name, hsize_t dims[3])
{
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
    if (ds < 0)
        return -1;
    hid_t sp = H5Dget_space(ds);
    int r = H5Sget_simple_extent_dims(sp, dims, NULL);
    H5Sclose(sp);
    H5Dclose(ds);
    return r;
}

static int ds_read(hid_t f, const char *name, hid_t type, void *buf)
{
    hid_t ds = H5Dopen2(f, name, H5P_DEFAULT);
    if (ds < 0)
        return -1;
    herr_t rc = H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
    H5Dclose(ds);
    return rc < 0 ? -1 : 0;
}

/* Two files hold the same bytes (both exist). */
static int same_file_bytes(const char *pa, const char *pb)
{
    FILE *fa = fopen(pa, "rb"), *fb = fopen(pb, "rb");
    int same = fa && fb;
    while (same) {
        int a = fgetc(fa), b = fgetc(fb);
        same = a == b;
        if (a == EOF || b == EOF)
            break;
    }
    if (fa)
        fclose(fa);
    if (fb)
        fclose(fb);
    return same;
}

static void test_bodies(const char *dir, int dim)
{
    lahar_case c;
    make_case(&c, dim);
    c.forces_interval = dim == 3 ? 0.0 : 0.05;
    char err[512];
    lahar_body_output *o = lahar_body_output_open(dir, &c, err, sizeof err);
    CHECK(o != NULL, "open: %s", err);
    if (!o) {
        free_case();
        return;
    }
    lahar_body_state st[4];
    lahar_body_report rep[4];
    const int nsnap = 3, nrow = 20;
    for (int k = 0; k < nsnap; k++) {
        for (int b = 0; b < 4; b++)
            state_at(b, k, &st[b]);
        CHECK(lahar_body_output_snapshot(o, 10 * k, 0.1 * k, st) == 0, "snapshot %d", k);
    }
    for (int k = 0; k < nrow; k++) {
        for (int b = 0; b < 4; b++) {
            memset(&rep[b], 0, sizeof rep[b]);
            rep[b].force[0] = k + 0.25 * b, rep[b].force[2] = -k;
            rep[b].torque[1] = 2.0 * k;
            rep[b].ncontacts = (k + b) % 3;
        }
        CHECK(lahar_body_output_forces(o, k, 0.01 * k, rep) == 0, "forces row %d", k);
    }
    /* the twin a snapshot is written into first (common/io/output_snapfile.c) has caught up with
     * the published file, byte for byte, and is removed at close */
    char path[1200], twin[1200];
    snprintf(path, sizeof path, "%s/bodies.h5", dir);
    snprintf(twin, sizeof twin, "%s/.bodies.h5.twin", dir);
    CHECK(same_file_bytes(path, twin), "%s is not bytewise %s while the writer is open", twin, path);
    lahar_body_output_close(o);
    CHECK(access(twin, F_OK) != 0, "%s is left after close", twin);

    hid_t f = open_ro(path);
    CHECK(f >= 0, "reopen %s", path);
    if (f >= 0) {
        hsize_t d[3];
        int64_t dimv = 0;
        hid_t a = H5Aopen_by_name(f, "header", "dimensions", H5P_DEFAULT, H5P_DEFAULT);
        H5Aread(a, H5T_NATIVE_INT64, &dimv);
        H5Aclose(a);
        CHECK(dimv == dim, "header dimensions %ld", (long)dimv);
        CHECK(ds_dims(f, "/header/mass", d) == 1 && d[0] == 4, "header mass shape");
        CHECK(ds_dims(f, "/header/inertia", d) == 2 && d[0] == 4 && d[1] == 3, "header inertia shape");
        double mass[4];
        ds_read(f, "/header/mass", H5T_NATIVE_DOUBLE, mass);
        CHECK(mass[1] == 2.0, "mass[1] = %g", mass[1]);
        char *names[4] = {0};
        hid_t st_t = H5Tcopy(H5T_C_S1);
        H5Tset_size(st_t, H5T_VARIABLE);
        H5Tset_cset(st_t, H5T_CSET_UTF8);
        CHECK(ds_read(f, "/header/body_name", st_t, names) == 0 && names[2] && strcmp(names[2], "floor") == 0,
              "body_name[2]");
        hid_t nds = H5Dopen2(f, "/header/body_name", H5P_DEFAULT);
        hid_t nsp = H5Dget_space(nds);
        H5Dvlen_reclaim(st_t, nsp, H5P_DEFAULT, names);
        H5Sclose(nsp), H5Dclose(nds), H5Tclose(st_t);
        /* the crate's body-frame mesh and its world vertices in snapshot 2 */
        int npc = dim == 2 ? 2 : 3;
        CHECK(ds_dims(f, "/geometry/bodies/000001/vertices", d) == 2 && d[1] == 3, "crate mesh");
        int nv1 = (int)d[0];
        double (*mv)[3] = malloc(sizeof *mv * (size_t)nv1);
        ds_read(f, "/geometry/bodies/000001/vertices", H5T_NATIVE_DOUBLE, mv);
        CHECK(ds_dims(f, "/geometry/bodies/000000/vertices", d) == 2, "ball mesh");
        int nv0 = (int)d[0];
        CHECK(ds_dims(f, "/geometry/moving/cells", d) == 2 && (int)d[1] == npc, "moving cells shape");
        CHECK(ds_dims(f, "/snapshots/000002/vertices", d) == 2 && (int)d[0] >= nv0 + nv1, "snapshot vertices");
        int nvm = (int)d[0];
        float *wv = malloc(sizeof *wv * 3 * (size_t)nvm), *wu = malloc(sizeof *wu * 3 * (size_t)nvm);
        ds_read(f, "/snapshots/000002/vertices", H5T_NATIVE_FLOAT, wv);
        ds_read(f, "/snapshots/000002/vertex_velocity", H5T_NATIVE_FLOAT, wu);
        lahar_body_state s1;
        state_at(1, 2, &s1);
        double maxe = 0.0, maxu = 0.0;
        for (int i = 0; i < nv1; i++) {
            vec3 r = q_rotate(q_load(s1.q), v3_load(mv[i]));
            vec3 p = v3_add(v3_load(s1.x), r), u = v3_add(v3_load(s1.v), v3_cross(v3_load(s1.w), r));
            const float *g = wv + 3 * (nv0 + i), *h = wu + 3 * (nv0 + i);
            maxe = fmax(maxe, v3_norm(v3_sub(p, v3(g[0], g[1], g[2]))));
            maxu = fmax(maxu, v3_norm(v3_sub(u, v3(h[0], h[1], h[2]))));
        }
        CHECK(maxe < 1e-6 && maxu < 1e-6, "world display vertices off by %g m, velocities by %g m/s", maxe, maxu);
        free(mv), free(wv), free(wu);
        double pos[4][3];
        ds_read(f, "/snapshots/000001/position", H5T_NATIVE_DOUBLE, pos);
        lahar_body_state s31;
        state_at(3, 1, &s31);
        CHECK(memcmp(pos[3], s31.x, sizeof pos[3]) == 0, "snapshot position bitwise");
        double t = -1;
        a = H5Aopen_by_name(f, "/snapshots/000002", "time", H5P_DEFAULT, H5P_DEFAULT);
        H5Aread(a, H5T_NATIVE_DOUBLE, &t);
        H5Aclose(a);
        CHECK(t == 0.1 * 2, "snapshot time %g", t);
        H5Fclose(f);
    }

    snprintf(path, sizeof path, "%s/forces.h5", dir);
    f = open_ro(path);
    CHECK(f >= 0, "reopen %s", path);
    if (f >= 0) {
        hsize_t d[3];
        /* interval 0: every row; interval 0.05 with rows every 0.01: t = 0, 0.05, ..., 0.15 */
        int expect = dim == 3 ? nrow : 4;
        CHECK(ds_dims(f, "t", d) == 1 && (int)d[0] == expect, "forces rows %d, expected %d", (int)d[0], expect);
        CHECK(ds_dims(f, "force", d) == 3 && (int)d[0] == expect && d[1] == 4 && d[2] == 3, "force shape");
        CHECK(ds_dims(f, "ncontacts", d) == 2 && (int)d[0] == expect && d[1] == 4, "ncontacts shape");
        double *frc = malloc(sizeof *frc * (size_t)expect * 12), *tt = malloc(sizeof *tt * (size_t)expect);
        int64_t *stp = malloc(sizeof *stp * (size_t)expect);
        ds_read(f, "force", H5T_NATIVE_DOUBLE, frc);
        ds_read(f, "t", H5T_NATIVE_DOUBLE, tt);
        ds_read(f, "step", H5T_NATIVE_INT64, stp);
        int stride = dim == 3 ? 1 : 5;
        for (int r = 0; r < expect; r++) {
            int k = r * stride;
            CHECK(stp[r] == k && tt[r] == 0.01 * k, "row %d: step %ld t %g", r, (long)stp[r], tt[r]);
            CHECK(frc[(r * 4 + 3) * 3 + 0] == k + 0.75 && frc[(r * 4 + 3) * 3 + 2] == -k, "row %d force", r);
        }
        free(frc), free(tt), free(stp);
        H5Fclose(f);
    }
    free_case();
}

static void test_particles(const char *dir)
{
    lahar_case c;
    make_case(&c, 2);
    c.sph_dx = 0.01;
    c.sph_density = 1000;
    char err[512];
    unsigned fields = LAHAR_PFIELD_VELOCITY | LAHAR_PFIELD_DENSITY | LAHAR_PFIELD_ID;
    lahar_particle_output *o = lahar_particle_output_open(dir, &c, fields, err, sizeof err);
    CHECK(o != NULL, "particle open: %s", err);
    enum { N = 50 };
    double x[N], y[N], vx[N], vy[N], vz[N], rho[N];
    int64_t id[N];
    for (int k = 0; o && k < 3; k++) {
        for (int i = 0; i < N; i++) {
            x[i] = 0.01 * i, y[i] = 0.1 * k, vx[i] = i, vy[i] = -k, vz[i] = 0, rho[i] = 1000 + i, id[i] = 100 + i;
        }
        lahar_particles_view v = {.n = N, .x = x, .y = y, .vx = vx, .vy = vy, .vz = vz, .density = rho, .id = id};
        /* particle snapshots at the same steps as the body snapshots (0, 10, 20) */
        CHECK(lahar_particle_output_snapshot(o, 10 * k, 0.1 * k, &v) == 0, "particle snapshot %d", k);
    }
    lahar_particle_output_close(o);
    char path[1200];
    snprintf(path, sizeof path, "%s/particles.h5", dir);
    hid_t f = open_ro(path);
    CHECK(f >= 0, "reopen particles");
    if (f >= 0) {
        hsize_t d[3];
        double z[N], r2[N];
        int64_t id2[N];
        CHECK(ds_dims(f, "/snapshots/000002/x", d) == 1 && d[0] == N, "x shape");
        CHECK(ds_read(f, "/snapshots/000002/z", H5T_NATIVE_DOUBLE, z) == 0 && z[7] == 0.0, "2D z reads as zeros");
        CHECK(ds_read(f, "/snapshots/000001/density", H5T_NATIVE_DOUBLE, r2) == 0 && r2[9] == 1009, "density");
        CHECK(ds_read(f, "/snapshots/000001/id", H5T_NATIVE_INT64, id2) == 0 && id2[49] == 149, "id");
        CHECK(H5Lexists(f, "/snapshots/000001/pressure", H5P_DEFAULT) == 0, "pressure not selected but written");
        H5Fclose(f);
    }
    free_case();
}

static int same_bytes(const char *da, const char *db, const char *name)
{
    char pa[1200], pb[1200];
    snprintf(pa, sizeof pa, "%s/%s", da, name);
    snprintf(pb, sizeof pb, "%s/%s", db, name);
    return same_file_bytes(pa, pb);
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "test_output_dir";
    char d3[1000], d2[1000];
    snprintf(d3, sizeof d3, "%s/3d", dir);
    snprintf(d2, sizeof d2, "%s/2d", dir);
    mkdir(dir, 0755), mkdir(d3, 0755), mkdir(d2, 0755);
    test_meshes();
    test_bodies(d3, 3);
    test_bodies(d2, 2);
    test_particles(d2);
    /* the same output written again is the same bytes (no object time stamps) */
    char d3b[1000];
    snprintf(d3b, sizeof d3b, "%s/3d_again", dir);
    mkdir(d3b, 0755);
    test_bodies(d3b, 3);
    CHECK(same_bytes(d3, d3b, "bodies.h5") && same_bytes(d3, d3b, "bodies.xmf"), "bodies.h5/.xmf differ between two writes");
    /* a missing output directory: NULL, one message naming the file, nothing leaked (ASan) */
    lahar_case c;
    make_case(&c, 3);
    char err[512] = "";
    lahar_body_output *o = lahar_body_output_open("/nonexistent/lahar_out", &c, err, sizeof err);
    CHECK(o == NULL && strstr(err, "/nonexistent/lahar_out/bodies.h5"), "open in a missing directory: %s", err);
    free_case();
    if (failures) {
        fprintf(stderr, "test_output: %d failure(s)\n", failures);
        return 1;
    }
    printf("test_output: all checks passed\n");
    return 0;
}
