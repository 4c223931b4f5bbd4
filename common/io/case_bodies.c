/* The case loader: bodies: and terrain: (shapes, mass properties, overlaps at t = 0) and the
 * point-in-body test of a loaded case. */
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "case_reader.h"
#include "geometry.h"
#include "terrain.h"
#include "vec.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* --- bodies -------------------------------------------------------------------------------------- */

enum { SH_SPHERE, SH_DISC, SH_BOX, SH_SEGMENT, SH_POLYLINE, SH_POLYGON, SH_POLYHEDRON, SH_PLANE, SH_STL, SH_N };
/* the shape's name: the key table's choices of bodies[].shape, in the order of SH_* */
static const char *shape_name(int kind)
{
    return lahar_key_find(lahar_key_section_find("bodies[]"), "shape")->choices[kind];
}
/* 2: 2D only, 3: 3D only, 0: both */
static const int shape_dim[SH_N] = {3, 2, 0, 0, 2, 2, 3, 3, 3};
static const int shape_fixed_only[SH_N] = {0, 0, 0, 0, 1, 0, 0, 1, 1};

/* Read a list of points (each `dim` numbers) into a new array of 3-vectors (z = 0 in 2D). */
double (*case_read_points(reader *r, yaml_node_t *n, const char *key, int dim, int *np))[3]
{
    if (r->failed)
        return NULL;
    if (n->type != YAML_SEQUENCE_NODE || rd_seq_len(n) == 0) {
        rd_fail(r, n, key, "expected a non-empty list of points like [[x, y%s], ...], got %s", dim == 3 ? ", z" : "",
                n->type == YAML_SEQUENCE_NODE ? "an empty list" : rd_node_kind(n));
        return NULL;
    }
    int cnt = rd_seq_len(n);
    double (*p)[3] = calloc((size_t)cnt, sizeof *p);
    if (!p) {
        rd_fail(r, n, key, "out of memory");
        return NULL;
    }
    for (int i = 0; i < cnt; i++) {
        char ik[KEY_MAX];
        snprintf(ik, sizeof ik, "%.*s[%d]", KEY_MAX - 16, key, i);
        if (!rd_vec(r, rd_seq_item(r, n, i), ik, dim, p[i])) {
            free(p);
            return NULL;
        }
    }
    *np = cnt;
    return p;
}

/* Faces: a list of lists of vertex indices -> face_start (nf + 1) and face_v. */
static int read_faces(reader *r, yaml_node_t *n, const char *key, int **fs, int **fv, int *nf)
{
    if (n->type != YAML_SEQUENCE_NODE || rd_seq_len(n) == 0) {
        rd_fail(r, n, key, "expected a non-empty list of faces like [[0, 1, 2], ...], got %s",
                n->type == YAML_SEQUENCE_NODE ? "an empty list" : rd_node_kind(n));
        return -1;
    }
    int cnt = rd_seq_len(n), total = 0;
    for (int f = 0; f < cnt; f++) {
        yaml_node_t *fn = rd_seq_item(r, n, f);
        if (fn->type != YAML_SEQUENCE_NODE) {
            char ik[KEY_MAX];
            snprintf(ik, sizeof ik, "%.*s[%d]", KEY_MAX - 16, key, f);
            rd_fail(r, fn, ik, "expected a list of vertex indices like [0, 1, 2], got %s", rd_node_kind(fn));
            return -1;
        }
        total += rd_seq_len(fn);
    }
    *fs = calloc((size_t)(unsigned)cnt + 1, sizeof **fs);
    *fv = calloc((size_t)(total ? total : 1), sizeof **fv);
    if (!*fs || !*fv) {
        free(*fs);
        free(*fv);
        rd_fail(r, n, key, "out of memory");
        return -1;
    }
    int k = 0;
    for (int f = 0; f < cnt; f++) {
        yaml_node_t *fn = rd_seq_item(r, n, f);
        (*fs)[f] = k;
        for (int i = 0; i < rd_seq_len(fn); i++) {
            char ik[KEY_MAX + 32];
            snprintf(ik, sizeof ik, "%.*s[%d][%d]", KEY_MAX - 8, key, f, i);
            double v;
            if (rd_number(r, rd_seq_item(r, fn, i), ik, &v) != 0 || v != floor(v) || v < 0 || v > INT_MAX) {
                rd_fail(r, rd_seq_item(r, fn, i), ik, "expected a vertex index (an integer >= 0)");
                free(*fs);
                free(*fv);
                return -1;
            }
            (*fv)[k++] = (int)v;
        }
    }
    (*fs)[cnt] = k;
    *nf = cnt;
    return 0;
}

/* Mass properties per identical local shape: thousands of copies of one rock cost one computation. */
typedef struct {
    uint64_t hash;
    int dim;
    lahar_shape local;      /* as built, before the principal transform (the lookup key) */
    lahar_shape principal;  /* moved to the principal frame */
    lahar_mass_props mp;    /* unit density */
} mass_cache_entry;

typedef struct {
    int n, cap;
    mass_cache_entry *e;
} mass_cache;

static uint64_t case_fnv1a(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

static uint64_t shape_hash(const lahar_shape *s, int dim)
{
    uint64_t h = 1469598103934665603ull;
    h = case_fnv1a(h, &dim, sizeof dim);
    h = case_fnv1a(h, &s->radius, sizeof s->radius);
    h = case_fnv1a(h, &s->nv, sizeof s->nv);
    h = case_fnv1a(h, &s->nf, sizeof s->nf);
    h = case_fnv1a(h, s->v, (size_t)s->nv * sizeof *s->v);
    if (s->nf)
        h = case_fnv1a(h, s->face_v, (size_t)s->face_start[s->nf] * sizeof *s->face_v);
    return h;
}

static int shape_equal(const lahar_shape *a, const lahar_shape *b)
{
    if (a->nv != b->nv || a->ne != b->ne || a->nf != b->nf || a->radius != b->radius)
        return 0;
    if (memcmp(a->v, b->v, (size_t)a->nv * sizeof *a->v) != 0 || memcmp(a->e, b->e, (size_t)a->ne * sizeof *a->e) != 0)
        return 0;
    if (a->nf && (memcmp(a->face_start, b->face_start, ((size_t)a->nf + 1) * sizeof *a->face_start) != 0 ||
                  memcmp(a->face_v, b->face_v, (size_t)a->face_start[a->nf] * sizeof *a->face_v) != 0))
        return 0;
    return 1;
}

static void mass_cache_free(mass_cache *mc)
{
    for (int i = 0; i < mc->n; i++) {
        lahar_shape_free(&mc->e[i].local);
        lahar_shape_free(&mc->e[i].principal);
    }
    free(mc->e);
    memset(mc, 0, sizeof *mc);
}

/* Replace *s (local frame) by its principal-frame version and give its unit-density properties. */
static int mass_cache_apply(mass_cache *mc, lahar_shape *s, int dim, lahar_mass_props *mp, char *err, size_t errlen)
{
    uint64_t h = shape_hash(s, dim);
    for (int i = 0; i < mc->n; i++)
        if (mc->e[i].hash == h && mc->e[i].dim == dim && shape_equal(&mc->e[i].local, s)) {
            lahar_shape_free(s);
            *mp = mc->e[i].mp;
            return lahar_shape_copy(s, &mc->e[i].principal);
        }
    if (lahar_shape_mass_properties(s, dim, mp, err, errlen) != 0)
        return -1;
    if (mc->n == mc->cap) {
        int cap = mc->cap ? 2 * mc->cap : 16;
        mass_cache_entry *t = realloc(mc->e, (size_t)cap * sizeof *t);
        if (!t)
            return -1;
        mc->e = t;
        mc->cap = cap;
    }
    mass_cache_entry *e = &mc->e[mc->n];
    memset(e, 0, sizeof *e);
    if (lahar_shape_copy(&e->local, s) != 0)
        return -1;
    lahar_shape_to_principal(s, mp);
    if (lahar_shape_copy(&e->principal, s) != 0) {
        lahar_shape_free(&e->local);
        return -1;
    }
    e->hash = h;
    e->dim = dim;
    e->mp = *mp;
    mc->n++;
    return 0;
}

/* Build the body's shape in its local frame (coordinates relative to `position`, before the
 * orientation). Returns 0 or -1 (message already reported). */
/* shape: box, size: the OUTER size; the core is size - 2 radius. */
static int shape_from_box(reader *r, rmap *m, double radius, lahar_shape *s)
{
    const int dim = r->dim;
    double size[3] = {0, 0, 0}, half[3] = {0, 0, 0};
    rmap_vec(m, "size", dim, size, 1, dim == 3 ? "[0.2, 0.1, 0.1]" : "[0.2, 0.1]");
    if (r->failed)
        return -1;
    for (int k = 0; k < dim; k++) {
        if (!(size[k] > 2.0 * radius)) {
            rmap_fail(m, "size", "every side must be > 2 radius = %g m (got %g); size is the OUTER size, the "
                      "core is size - 2 radius", 2.0 * radius, size[k]);
            return -1;
        }
        half[k] = 0.5 * size[k] - radius;
    }
    return dim == 3 ? lahar_shape_make_box(s, half, radius) : lahar_shape_make_box2d(s, half, radius);
}

/* shape: plane, a rectangle of `size` with outward `normal`. */
static int shape_from_plane(reader *r, rmap *m, double radius, lahar_shape *s)
{
    double size[2] = {0, 0}, nrm[3] = {0, 0, 0}, zero[3] = {0, 0, 0};
    rmap_vec(m, "normal", 3, nrm, 1, "[0, 0, 1]");
    rmap_vec(m, "size", 2, size, 1, "[1.0, 1.0]");
    if (r->failed)
        return -1;
    if (!(v3_norm(v3_load(nrm)) > 0)) {
        rmap_fail(m, "normal", "must not be the zero vector; it is the outward normal of the rectangle");
        return -1;
    }
    if (!(size[0] > 0 && size[1] > 0)) {
        rmap_fail(m, "size", "both sides must be > 0 m (got [%g, %g])", size[0], size[1]);
        return -1;
    }
    return lahar_shape_make_plane(s, zero, nrm, size, radius);
}

/* shape: polyhedron with `faces:` (counter-clockwise seen from outside); a moving body must be
 * convex. */
static int shape_from_faces(reader *r, rmap *m, yaml_node_t *fn, const double (*p)[3], int np, int motion,
                            double radius, lahar_shape *s)
{
    int *fs = NULL, *fv = NULL, nf = 0, rc = -1;
    char fkey[KEY_MAX], err[512] = "";
    rd_key_join(m->prefix, "faces", fkey);
    if (read_faces(r, fn, fkey, &fs, &fv, &nf) != 0)
        return -1;
    rc = lahar_shape_make_polyhedron(s, p, np, fs, fv, nf, radius, err, sizeof err);
    if (rc != 0)
        rd_fail(r, fn, fkey, "%s; fix the faces or drop `faces:` to use the convex hull of the vertices", err);
    else if (lahar_shape_core_volume(s) <= 0) {
        rd_fail(r, fn, fkey, "the faces are clockwise seen from outside (the core volume is %g); list every "
                "face's vertices counter-clockwise seen from outside", lahar_shape_core_volume(s));
        lahar_shape_free(s);
        rc = -1;
    } else if (motion != LAHAR_MOTION_FIXED) {
        double L = 0;
        for (int i = 0; i < np; i++)
            L = fmax(L, v3_norm(v3_load(p[i])));
        if (!lahar_shape_is_convex(s, 3, 1e-9 * (L > 0 ? L : 1))) {
            rd_fail(r, fn, fkey, "the polyhedron is not convex, but moving bodies must be convex; drop `faces:` to "
                    "use the convex hull, or split the body");
            lahar_shape_free(s);
            rc = -1;
        }
    }
    free(fs);
    free(fv);
    return rc;
}

/* The shapes made of `vertices:`: segment (2 points), polyline (open or `closed`), polygon (their
 * convex hull, 2D), polyhedron (their convex hull, or `faces:`). */
static int shape_from_points(reader *r, rmap *m, int kind, int motion, double radius, lahar_shape *s)
{
    const int dim = r->dim;
    char key[KEY_MAX], err[512] = "";
    yaml_node_t *vn = rmap_get(m, "vertices");
    if (!vn) {
        rmap_missing(m, "vertices", dim == 3 ? "[[0, 0, 0], [1, 0, 0], ...]" : "[[0, 0], [1, 0], ...]");
        return -1;
    }
    rd_key_join(m->prefix, "vertices", key);
    int np = 0, rc = -1;
    yaml_node_t *fn = NULL; /* faces: of a polyhedron */
    double (*p)[3] = case_read_points(r, vn, key, dim, &np);
    if (!p)
        return -1;
    const double(*cp)[3] = (const double(*)[3])p;
    if (kind == SH_SEGMENT) {
        if (np != 2)
            rd_fail(r, vn, key, "a segment has exactly 2 vertices (got %d)", np);
        else if (v3_norm(v3_sub(v3_load(p[0]), v3_load(p[1]))) == 0.0)
            rd_fail(r, vn, key, "the two vertices coincide; use shape: %s for a single point",
                    dim == 3 ? "sphere" : "disc");
        else
            rc = lahar_shape_make_segment(s, p[0], p[1], radius);
    } else if (kind == SH_POLYLINE) {
        int closed = rd_key_bool(m, "closed");
        if (!r->failed) {
            rc = lahar_shape_make_polyline(s, cp, np, closed, radius, err, sizeof err);
            if (rc != 0)
                rd_fail(r, vn, key, "%s; fix the points", err);
        }
    } else if (kind == SH_POLYGON) {
        rc = lahar_shape_make_polygon_hull(s, cp, np, radius, err, sizeof err);
        if (rc != 0)
            rd_fail(r, vn, key, "%s; a polygon needs 3 or more points not on one line", err);
    } else if ((fn = rmap_get(m, "faces")) != NULL) {
        rc = shape_from_faces(r, m, fn, cp, np, motion, radius, s);
    } else {
        rc = lahar_shape_make_hull(s, cp, np, radius, err, sizeof err);
        if (rc != 0)
            rd_fail(r, vn, key, "%s; a polyhedron needs 4 or more points not all in one plane", err);
    }
    free(p);
    return rc;
}

/* shape: stl, `file` relative to the case file's directory, coordinates times `scale`. */
static int shape_from_stl(reader *r, rmap *m, double radius, lahar_shape *s)
{
    char err[512] = "";
    const char *file = rmap_str(m, "file", 1, NULL, "terrain.stl");
    double scale = rmap_num(m, "scale", 0, 1.0, "0.001");
    if (r->failed)
        return -1;
    if (!(scale > 0)) {
        rmap_fail(m, "scale", "must be > 0 (got %g); it multiplies the STL coordinates, e.g. 0.001 for mm", scale);
        return -1;
    }
    char full[2048];
    if (file[0] == '/')
        snprintf(full, sizeof full, "%s", file);
    else
        snprintf(full, sizeof full, "%s%s", r->dir, file);
    int rc = lahar_shape_read_stl(s, full, radius, err, sizeof err);
    if (rc != 0)
        rmap_fail(m, "file", "%s; STL paths are relative to the case file's directory", err);
    else
        lahar_shape_transform(s, NULL, NULL, scale);
    return rc;
}

static int build_shape(reader *r, rmap *m, int kind, int motion, lahar_shape *s)
{
    double radius = rmap_num(m, "radius", 1, 0.0, kind == SH_SPHERE || kind == SH_DISC ? "0.05" : "0.005");
    if (r->failed)
        return -1;
    if (!(radius > 0)) {
        rmap_fail(m, "radius", "must be > 0 m (got %g); %s", radius,
                  kind == SH_SPHERE || kind == SH_DISC ? "it is the sphere/disc radius"
                                                       : "it is the sweep (rounding) radius of the shape, small "
                                                         "compared with the body (e.g. 1-5 % of its size)");
        return -1;
    }
    int rc = -1;
    switch (kind) {
    case SH_SPHERE:
    case SH_DISC:
        rc = lahar_shape_make_sphere(s, radius);
        break;
    case SH_BOX:
        rc = shape_from_box(r, m, radius, s);
        break;
    case SH_PLANE:
        rc = shape_from_plane(r, m, radius, s);
        break;
    case SH_SEGMENT:
    case SH_POLYLINE:
    case SH_POLYGON:
    case SH_POLYHEDRON:
        rc = shape_from_points(r, m, kind, motion, radius, s);
        break;
    case SH_STL:
        rc = shape_from_stl(r, m, radius, s);
        break;
    default:
        break;
    }
    if (rc != 0 && !r->failed)
        rd_fail(r, m->node, m->prefix, "out of memory building the shape");
    return r->failed ? -1 : 0;
}

/* bodies[i].shape, and the keys of bodies[] (case_keys.c) that belong to it: -1 on error. */
static int read_body_shape_kind(rmap *m)
{
    const lahar_key_section *sec = lahar_key_section_find("bodies[]");
    m->sec = sec;
    int kind = rd_key_choice(m, "shape");
    if (m->r->failed)
        return -1;
    const char *keys[32];
    int nk = 0;
    for (const lahar_key *k = sec ? sec->keys : NULL; k && k->name && nk < 31; k++)
        if (lahar_key_applies(k, shape_name(kind)))
            keys[nk++] = k->name;
    keys[nk] = NULL;
    rmap_check_keys(m, keys);
    m->sec = sec;
    return kind;
}

/* bodies[i].material (read as mat): a DEM material of the materials: section, or the error naming
 * the closest one. */
static int find_body_material(rmap *m, const char *mat, const lahar_case *c, lahar_body *b)
{
    b->material = lahar_case_find_material(c, mat);
    if (b->material < 0) {
        const char *names[64];
        int nn = 0;
        for (int k = 0; k < c->nmaterial && nn < 63; k++)
            names[nn++] = c->materials[k].name;
        names[nn] = NULL;
        char list[512];
        rd_join_names(names, list, sizeof list);
        const char *near = rd_closest_name(mat, names);
        if (nn == 0)
            rmap_fail(m, "material", "unknown material '%s'; define it in the materials: section", mat);
        else if (near)
            rmap_fail(m, "material", "unknown material '%s'; did you mean '%s'? (materials: %s)", mat, near, list);
        else
            rmap_fail(m, "material", "unknown material '%s'; define it in materials: (defined: %s)", mat, list);
        return -1;
    }
    if (c->materials[b->material].model == LAHAR_CONTACT_SOIL) {
        rmap_fail(m, "material", "'%s' is an SPH soil (model: soil); a body needs a DEM material (model: hertz or "
                  "linear)", mat);
        return -1;
    }
    return 0;
}

/* Where a body starts and how it moves: bodies[i].position, orientation, velocity and
 * angular_velocity (the velocities: has_v, has_w when given). */
typedef struct {
    double pos[3], vel[3], omega[3];
    quat q;
    int has_v, has_w;
} body_start;

static void read_body_orientation(rmap *m, yaml_node_t *on, quat *q)
{
    static const char *const okeys3[] = {"axis", "angle_deg", NULL};
    static const char *const okeys2[] = {"angle_deg", NULL};
    const int dim = m->r->dim;
    char ok[KEY_MAX];
    rd_key_join(m->prefix, "orientation", ok);
    rmap om;
    if (rmap_open(m->r, on, ok, &om) != 0)
        return;
    rmap_check_keys(&om, dim == 3 ? okeys3 : okeys2);
    double axis[3] = {0, 0, 1};
    if (dim == 3)
        rmap_vec(&om, "axis", 3, axis, 0, "");
    double ang = rmap_num(&om, "angle_deg", 1, 0.0, "30");
    if (!m->r->failed && !(v3_norm(v3_load(axis)) > 0))
        rmap_fail(&om, "axis", "must not be the zero vector");
    *q = q_axis_angle(v3_normalize(v3_load(axis)), ang * M_PI / 180.0);
}

static int read_body_start(rmap *m, lahar_motion motion, body_start *bs)
{
    const int dim = m->r->dim;
    memset(bs, 0, sizeof *bs);
    rmap_vec(m, "position", dim, bs->pos, 0, "");
    bs->q = q_identity();
    yaml_node_t *on = rmap_get(m, "orientation");
    if (on && !m->r->failed)
        read_body_orientation(m, on, &bs->q);
    bs->has_v = rmap_vec(m, "velocity", dim, bs->vel, 0, "");
    if (dim == 3)
        bs->has_w = rmap_vec(m, "angular_velocity", 3, bs->omega, 0, "");
    else if (rmap_get(m, "angular_velocity")) {
        bs->omega[2] = rmap_num(m, "angular_velocity", 0, 0.0, "");
        bs->has_w = 1;
    }
    if (m->r->failed)
        return -1;
    if (motion == LAHAR_MOTION_FIXED && (bs->has_v || bs->has_w)) {
        rmap_fail(m, bs->has_v ? "velocity" : "angular_velocity", "a fixed body does not move; remove it, or use "
                  "`motion: prescribed` for a wall that moves at a given velocity");
        return -1;
    }
    return 0;
}

/* A wall keeps world-frame geometry with identity orientation; mass 0 marks it immovable. The
 * convexity test costs faces x vertices: large meshes (terrain) are marked non-convex, which only
 * means the engine treats them with the general mesh path. */
static void place_fixed_body(lahar_body *b, const body_start *bs, int dim)
{
    double R[3][3];
    q_to_rotmat(bs->q, R);
    lahar_shape *s = &b->shape;
    lahar_shape_transform(s, (const double(*)[3])R, bs->pos, 1.0);
    b->q[0] = 1.0;
    b->convex = (double)s->nf * s->nv <= 5e7 && lahar_shape_is_convex(s, dim, 1e-9 * (s->radius + 1.0));
}

/* A moving body: its mass properties from the shape and the material's density, its position at
 * the centre of mass and its orientation along the principal axes. */
static void place_moving_body(reader *r, yaml_node_t *n, const char *prefix, const lahar_case *c, mass_cache *mc,
                              lahar_body *b, const body_start *bs)
{
    char err[256] = "";
    lahar_mass_props mp;
    if (mass_cache_apply(mc, &b->shape, r->dim, &mp, err, sizeof err) != 0) {
        rd_fail(r, n, prefix, "cannot compute mass properties: %s", err[0] ? err : "out of memory");
        return;
    }
    double rho = c->materials[b->material].density;
    b->convex = 1;
    b->mass = rho * mp.volume;
    for (int k = 0; k < 3; k++)
        b->inertia[k] = rho * mp.inertia[k];
    vec3 com = q_rotate(bs->q, v3_load(mp.com));
    v3_store(v3_add(v3_load(bs->pos), com), b->x);
    quat qb = q_normalize(q_mul(bs->q, q_from_rotmat((const double(*)[3])mp.axes)));
    q_store(qb, b->q);
    memcpy(b->v, bs->vel, sizeof bs->vel);
    memcpy(b->w, bs->omega, sizeof bs->omega);
}

static void read_body(reader *r, yaml_node_t *n, int i, lahar_case *c, mass_cache *mc)
{
    const int dim = r->dim;
    char prefix[KEY_MAX];
    snprintf(prefix, sizeof prefix, "bodies[%d]", i);
    rmap m;
    if (rmap_open(r, n, prefix, &m) != 0)
        return;
    lahar_body *b = &c->bodies[i];
    int kind = read_body_shape_kind(&m);
    if (kind < 0)
        return;
    char defname[LAHAR_NAME_MAX];
    snprintf(defname, sizeof defname, "body%d", i);
    rmap_name(&m, "name", 0, defname, b->name);
    for (int j = 0; j < i && !r->failed; j++)
        if (strcmp(c->bodies[j].name, b->name) == 0)
            rmap_fail(&m, "name", "'%s' is already the name of bodies[%d]; body names must be unique", b->name, j);
    if (r->failed)
        return;
    if (shape_dim[kind] && shape_dim[kind] != dim) {
        static const char *const alt[SH_N] = {"disc", "sphere", "", "", "segment or stl", "box or polyhedron",
                                              "polygon", "polyline", "polyline"};
        rmap_fail(&m, "shape", "'%s' is a %dD shape but the case has dimensions: %d; use %s", shape_name(kind),
                  shape_dim[kind], dim, alt[kind]);
        return;
    }
    b->motion = (lahar_motion)rd_key_choice(&m, "motion");
    b->record_contacts = rd_key_bool(&m, "record_contacts");
    const char *mat = rmap_str(&m, "material", 1, NULL, c->nmaterial ? c->materials[0].name : "rock");
    if (r->failed)
        return;
    if (shape_fixed_only[kind] && b->motion != LAHAR_MOTION_FIXED) {
        rmap_fail(&m, "shape", "'%s' bodies can only be walls: add `motion: fixed`%s", shape_name(kind),
                  kind == SH_STL ? " (STL surfaces may be open and non-convex)" : "");
        return;
    }
    body_start bs;
    if (find_body_material(&m, mat, c, b) != 0 || read_body_start(&m, b->motion, &bs) != 0 ||
        build_shape(r, &m, kind, b->motion, &b->shape) != 0)
        return;
    if (b->motion == LAHAR_MOTION_FIXED)
        place_fixed_body(b, &bs, dim);
    else
        place_moving_body(r, n, prefix, c, mc, b, &bs);
}

static void read_body_list(reader *r, yaml_node_t *n, lahar_case *c, mass_cache *mc, int *line)
{
    if (n->type != YAML_SEQUENCE_NODE) {
        rd_fail(r, n, "bodies", "expected a list of bodies (lines starting with `- `), got %s", rd_node_kind(n));
        return;
    }
    int nb = rd_seq_len(n);
    c->bodies = calloc((size_t)(nb ? nb : 1), sizeof *c->bodies);
    if (!c->bodies) {
        rd_fail(r, n, "bodies", "out of memory");
        return;
    }
    for (int i = 0; i < nb && !r->failed; i++) {
        c->nbody = i + 1;
        yaml_node_t *bn = rd_seq_item(r, n, i);
        line[i] = (int)bn->start_mark.line + 1;
        read_body(r, bn, i, c, mc);
    }
}

void case_read_bodies(reader *r, yaml_node_t *n, lahar_case *c)
{
    int nb = n->type == YAML_SEQUENCE_NODE ? rd_seq_len(n) : 0;
    int *line = calloc((size_t)(nb ? nb : 1), sizeof *line);
    mass_cache mc = {0, 0, NULL};
    if (!line)
        rd_fail(r, n, "bodies", "out of memory");
    else
        read_body_list(r, n, c, &mc, line);
    mass_cache_free(&mc);
    free(line);
}

/* terrain: {file | points, material, radius, name}: one fixed body appended to the bodies, a chain
 * of segments (2D: the points, or a CSV of x,y) or two triangles per grid cell (3D: an ESRI ASCII
 * grid .asc); terrain.h. The polyline / grid stays in the reader for sph.blocks[i].between. */
void case_read_terrain(reader *r, yaml_node_t *n, lahar_case *c)
{
    if (!n || r->failed)
        return;
    r->terrain_node = n;
    rmap m;
    if (rmap_open(r, n, "terrain", &m) != 0)
        return;
    rmap_section(&m, "terrain");
    const int dim = r->dim;
    char name[LAHAR_NAME_MAX];
    rmap_name(&m, "name", 0, "terrain", name);
    const char *mat = rmap_str(&m, "material", 1, NULL, c->nmaterial ? c->materials[0].name : "bed");
    double radius = rmap_num(&m, "radius", 1, 0.0, "0.05");
    yaml_node_t *fn = rmap_get(&m, "file"), *pn = rmap_get(&m, "points");
    if (r->failed)
        return;
    if (!(radius > 0)) {
        rmap_fail(&m, "radius", "must be > 0 m (got %g); it is the sweep radius of the terrain surface (the "
                  "surface lies radius above the points), e.g. dx/4", radius);
        return;
    }
    if (lahar_case_find_body(c, name) >= 0) {
        rmap_fail(&m, "name", "'%s' is already the name of a body; give the terrain another name", name);
        return;
    }
    int mi = lahar_case_find_material(c, mat);
    if (mi < 0 || c->materials[mi].model == LAHAR_CONTACT_SOIL) {
        rmap_fail(&m, "material", mi < 0 ? "unknown material '%s'; define it in the materials: section"
                                         : "'%s' is an SPH soil; the terrain needs a DEM material (model: hertz or "
                                           "linear; its friction is mu_phi against soil)", mat);
        return;
    }
    if (!!fn == !!pn) {
        rd_fail(r, n, "terrain", dim == 2 ? "give exactly one of points: [[x, y], ...] or file: profile.csv"
                                          : "give file: terrain.asc (an ESRI ASCII grid)");
        return;
    }
    if (dim == 3 && pn) {
        rmap_fail(&m, "points", "a 3D terrain is a heightmap: give file: terrain.asc (an ESRI ASCII grid)");
        return;
    }
    char err[1024] = "", full[2048] = "";
    if (fn) {
        const char *file = rmap_str(&m, "file", 1, NULL, "terrain.asc");
        if (r->failed)
            return;
        snprintf(full, sizeof full, "%s%s", file[0] == '/' ? "" : r->dir, file);
    }
    lahar_shape s;
    int rc;
    if (dim == 2) {
        if (pn) {
            r->terrain_pts = case_read_points(r, pn, "terrain.points", 2, &r->terrain_npts);
            if (!r->terrain_pts)
                return;
        } else if (lahar_profile_read_csv(full, &r->terrain_pts, &r->terrain_npts, err, sizeof err) != 0) {
            rmap_fail(&m, "file", "%s (paths are relative to the case file's directory)", err);
            return;
        }
        rc = lahar_shape_make_polyline(&s, (const double(*)[3])r->terrain_pts, r->terrain_npts, 0, radius, err,
                                       sizeof err);
        if (rc != 0) {
            rd_fail(r, pn ? pn : fn, pn ? "terrain.points" : "terrain.file", "%s; fix the points", err);
            return;
        }
    } else {
        if (lahar_heightmap_read_asc(full, &r->terrain_hm, err, sizeof err) != 0) {
            rmap_fail(&m, "file", "%s (paths are relative to the case file's directory)", err);
            return;
        }
        if (lahar_heightmap_shape(&r->terrain_hm, radius, &s, err, sizeof err) != 0) {
            rmap_fail(&m, "file", "%s: %s", full, err);
            return;
        }
    }
    lahar_body *nb = realloc(c->bodies, ((size_t)c->nbody + 1) * sizeof *nb);
    if (!nb) {
        lahar_shape_free(&s);
        rd_fail(r, n, "terrain", "out of memory");
        return;
    }
    c->bodies = nb;
    lahar_body *b = &c->bodies[c->nbody++];
    memset(b, 0, sizeof *b);
    r->terrain_radius = radius;
    snprintf(b->name, sizeof b->name, "%s", name);
    b->material = mi;
    b->motion = LAHAR_MOTION_FIXED;
    b->shape = s;
    b->q[0] = 1.0;
    b->convex = 0; /* the general mesh / polyline path */
}

/* Bodies must not interpenetrate at t = 0 (walls may meet each other). */
void case_check_overlaps(reader *r, yaml_node_t *bodies, lahar_case *c)
{
    int n = c->nbody;
    double (*ctr)[4] = malloc((size_t)(n ? n : 1) * sizeof *ctr); /* bounding sphere centre, radius */
    if (!ctr) {
        rd_fail(r, bodies, "bodies", "out of memory");
        return;
    }
    for (int i = 0; i < n; i++) {
        const lahar_body *b = &c->bodies[i];
        const lahar_shape *s = &b->shape;
        double lo[3], hi[3];
        for (int k = 0; k < 3; k++) {
            lo[k] = INFINITY;
            hi[k] = -INFINITY;
        }
        for (int v = 0; v < s->nv; v++) {
            vec3 w = geom_world_vertex(s, b->x, b->q, v);
            for (int k = 0; k < 3; k++) {
                lo[k] = fmin(lo[k], v3_get(w, k));
                hi[k] = fmax(hi[k], v3_get(w, k));
            }
        }
        for (int k = 0; k < 3; k++)
            ctr[i][k] = 0.5 * (lo[k] + hi[k]);
        ctr[i][3] = 0.5 * sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                               (hi[2] - lo[2]) * (hi[2] - lo[2])) + s->radius;
    }
    for (int j = 0; j < n && !r->failed; j++)
        for (int i = 0; i < j && !r->failed; i++) {
            const lahar_body *a = &c->bodies[i], *b = &c->bodies[j];
            if (a->motion != LAHAR_MOTION_FREE && b->motion != LAHAR_MOTION_FREE)
                continue;
            double dx = ctr[i][0] - ctr[j][0], dy = ctr[i][1] - ctr[j][1], dz = ctr[i][2] - ctr[j][2];
            if (sqrt(dx * dx + dy * dy + dz * dz) > ctr[i][3] + ctr[j][3])
                continue;
            double d = geom_body_core_distance(&a->shape, a->x, a->q, &b->shape, b->x, b->q);
            double halo = a->shape.radius + b->shape.radius;
            /* touching is fine, and so is an overlap below 1e-6 of the radii (rounding of
             * coordinates written with a few digits); anything more starts with a force kick */
            if (d < halo * (1.0 - 1e-6)) {
                char key[KEY_MAX];
                int listed = j < rd_seq_len(bodies);
                snprintf(key, sizeof key, listed ? "bodies[%d]" : "terrain", j);
                rd_fail(r, listed ? rd_seq_item(r, bodies, j) : r->terrain_node, key, "'%s' overlaps '%s' (bodies[%d]) by %.3g m at t = 0 (core "
                        "distance %.6g m < sum of radii %.6g m); move the bodies apart", b->name, a->name, i,
                        halo - d, d, halo);
            }
        }
    free(ctr);
}

int lahar_body_contains(const lahar_body *bd, int dim, const double x[3])
{
    const lahar_shape *s = &bd->shape;
    vec3 p = v3_load(x), cp;
    int feat;
    if (geom_point_body_core(s, bd->x, bd->q, p, &cp, &feat) < s->radius)
        return 1;
    /* the core's interior: geom_point_body_core measures to its boundary features only */
    return geom_point_in_core(s, bd->convex, dim, bd->x, bd->q, p);
}
