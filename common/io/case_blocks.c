/* The case loader: the particle blocks of sph.blocks (box, polygon, STL, between the terrain and
 * a profile; phase; initial fields from expressions or an HDF5 file). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <hdf5.h>
#include <matheval.h>
#include <yaml.h>

#include "case_reader.h"
#include "errmsg.h"
#include "geometry.h"
#include "terrain.h"

/* Edges of a closed surface are shared by exactly two triangles. Returns 0, or the number of
 * edges that are not (first one in *bad_a, *bad_b), or -1 out of memory. */
static int edge_pair_cmp(const void *x, const void *y)
{
    const int *a = x, *b = y;
    return a[0] != b[0] ? (a[0] > b[0]) - (a[0] < b[0]) : (a[1] > b[1]) - (a[1] < b[1]);
}

static int mesh_open_edges(const int (*tri)[3], int ntri, int *bad_a, int *bad_b)
{
    int ne = 3 * ntri;
    int (*e)[2] = malloc((size_t)(ne ? ne : 1) * sizeof *e);
    if (!e)
        return -1;
    for (int t = 0; t < ntri; t++)
        for (int k = 0; k < 3; k++) {
            int a = tri[t][k], b = tri[t][(k + 1) % 3];
            e[3 * t + k][0] = a < b ? a : b;
            e[3 * t + k][1] = a < b ? b : a;
        }
    qsort(e, (size_t)ne, sizeof *e, edge_pair_cmp);
    int bad = 0;
    for (int i = 0; i < ne;) {
        int j = i;
        while (j < ne && e[j][0] == e[i][0] && e[j][1] == e[i][1])
            j++;
        if (j - i != 2) {
            if (!bad) {
                *bad_a = e[i][0];
                *bad_b = e[i][1];
            }
            bad++;
        }
        i = j;
    }
    free(e);
    return bad;
}

/* Segments p0-p1 and q0-q1 (2D) properly intersect or touch. */
static int seg2_intersect(const double *p0, const double *p1, const double *q0, const double *q1)
{
    double d1 = (q1[0] - q0[0]) * (p0[1] - q0[1]) - (q1[1] - q0[1]) * (p0[0] - q0[0]);
    double d2 = (q1[0] - q0[0]) * (p1[1] - q0[1]) - (q1[1] - q0[1]) * (p1[0] - q0[0]);
    double d3 = (p1[0] - p0[0]) * (q0[1] - p0[1]) - (p1[1] - p0[1]) * (q0[0] - p0[0]);
    double d4 = (p1[0] - p0[0]) * (q1[1] - p0[1]) - (p1[1] - p0[1]) * (q1[0] - p0[0]);
    if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
        return 1;
    return 0;
}

static void check_block_polygon(reader *r, yaml_node_t *pn, const char *key, lahar_particle_block *pb);

static void read_block_polygon(reader *r, yaml_node_t *pn, const char *prefix, lahar_particle_block *pb)
{
    char key[KEY_MAX];
    rd_key_join(prefix, "polygon", key);
    if (r->dim != 2) {
        rd_fail(r, pn, key, "polygon blocks are 2D; in 3D use box or stl (a closed triangulated surface)");
        return;
    }
    int np = 0;
    double (*p)[3] = case_read_points(r, pn, key, 2, &np);
    if (!p)
        return;
    pb->kind = LAHAR_BLOCK_POLYGON;
    pb->vert = p;
    pb->nvert = np;
    check_block_polygon(r, pn, key, pb);
}

/* A polygon block must be simple, with at least 3 vertices and an area. */
static void check_block_polygon(reader *r, yaml_node_t *pn, const char *key, lahar_particle_block *pb)
{
    double(*p)[3] = pb->vert;
    const int np = pb->nvert;
    if (np < 3) {
        rd_fail(r, pn, key, "a polygon needs at least 3 vertices (got %d)", np);
        return;
    }
    double area = 0;
    for (int i = 0, j = np - 1; i < np; j = i++)
        area += p[j][0] * p[i][1] - p[i][0] * p[j][1];
    area *= 0.5;
    for (int i = 0; i < np && !r->failed; i++)
        for (int j = i + 1; j < np && !r->failed; j++) {
            int i1 = (i + 1) % np, j1 = (j + 1) % np;
            if (j == i1 || i == j1)
                continue; /* neighbouring edges share a vertex */
            if (seg2_intersect(p[i], p[i1], p[j], p[j1]))
                rd_fail(r, pn, key, "edges %d-%d and %d-%d cross each other; a polygon block must be simple (list "
                        "the vertices in order around the region)", i, i1, j, j1);
        }
    if (!r->failed && !(fabs(area) > 0))
        rd_fail(r, pn, key, "the polygon has zero area");
    lahar_particle_block_bounds(pb, 2);
}

static void read_block_stl(reader *r, yaml_node_t *sn, const char *prefix, lahar_particle_block *pb)
{
    static const char *const keys[] = {"file", "scale", "position", NULL};
    char key[KEY_MAX];
    rd_key_join(prefix, "stl", key);
    if (r->dim != 3) {
        rd_fail(r, sn, key, "stl blocks are 3D; in 2D use box or polygon");
        return;
    }
    rmap m;
    if (rmap_open(r, sn, key, &m) != 0)
        return;
    rmap_check_keys(&m, keys);
    const char *file = rmap_str(&m, "file", 1, NULL, "reservoir.stl");
    double scale = rmap_num(&m, "scale", 0, 1.0, "0.001");
    double pos[3] = {0, 0, 0};
    rmap_vec(&m, "position", 3, pos, 0, "");
    if (r->failed)
        return;
    if (!(scale > 0)) {
        rmap_fail(&m, "scale", "must be > 0 (got %g); it multiplies the STL coordinates, e.g. 0.001 for mm", scale);
        return;
    }
    if (strlen(file) >= sizeof pb->source) {
        rmap_fail(&m, "file", "path longer than %d characters", (int)sizeof pb->source - 1);
        return;
    }
    snprintf(pb->source, sizeof pb->source, "%s", file);
    char full[2048], err[512] = "";
    if (file[0] == '/')
        snprintf(full, sizeof full, "%s", file);
    else
        snprintf(full, sizeof full, "%s%s", r->dir, file);
    lahar_shape s;
    if (lahar_shape_read_stl(&s, full, 1.0, err, sizeof err) != 0) {
        rmap_fail(&m, "file", "%s; STL paths are relative to the case file's directory", err[0] ? err : "out of memory");
        return;
    }
    lahar_shape_transform(&s, NULL, NULL, scale);
    lahar_shape_transform(&s, NULL, pos, 1.0);
    pb->kind = LAHAR_BLOCK_MESH;
    pb->nvert = s.nv;
    pb->ntri = s.nf;
    pb->vert = malloc((size_t)s.nv * sizeof *pb->vert);
    pb->tri = malloc((size_t)(s.nf ? s.nf : 1) * sizeof *pb->tri);
    if (!pb->vert || !pb->tri) {
        lahar_shape_free(&s);
        rmap_fail(&m, "file", "out of memory");
        return;
    }
    memcpy(pb->vert, s.v, (size_t)s.nv * sizeof *pb->vert);
    for (int f = 0; f < s.nf; f++)
        for (int k = 0; k < 3; k++)
            pb->tri[f][k] = s.face_v[s.face_start[f] + k];
    lahar_shape_free(&s);
    int ea = 0, eb = 0;
    int open = mesh_open_edges((const int(*)[3])pb->tri, pb->ntri, &ea, &eb);
    if (open < 0)
        rmap_fail(&m, "file", "out of memory");
    else if (open > 0)
        rmap_fail(&m, "file", "'%s' is not a closed surface: %d edges are not shared by exactly two triangles "
                  "(first: between [%g, %g, %g] and [%g, %g, %g]); a fluid region must be watertight", file, open,
                  pb->vert[ea][0], pb->vert[ea][1], pb->vert[ea][2], pb->vert[eb][0], pb->vert[eb][1], pb->vert[eb][2]);
    lahar_particle_block_bounds(pb, 3);
}

/* between: {top: ...}: the region between the terrain (terrain: section) and an upper surface,
 * a polygon in 2D (top: [[x, y], ...] or top: profile.csv), a closed mesh in 3D (top: surface.asc
 * on the terrain's grid); terrain.h. */
static void read_block_between(reader *r, yaml_node_t *bn, const char *prefix, lahar_particle_block *pb)
{
    static const char *const keys[] = {"top", NULL};
    char key[KEY_MAX], tkey[KEY_MAX], err[1024] = "";
    rd_key_join(prefix, "between", key);
    if (!r->terrain_node) {
        rd_fail(r, bn, key, "a region between the terrain and a surface needs a terrain: section");
        return;
    }
    rmap m;
    if (rmap_open(r, bn, key, &m) != 0)
        return;
    rmap_check_keys(&m, keys);
    yaml_node_t *tn = rmap_get(&m, "top");
    if (!tn) {
        rmap_missing(&m, "top", r->dim == 2 ? "[[x, y], ...]  (or a CSV file of x,y)" : "surface.asc");
        return;
    }
    rd_key_join(key, "top", tkey);
    char full[2048] = "";
    if (tn->type == YAML_SCALAR_NODE) {
        const char *file = rd_scalar(tn);
        snprintf(full, sizeof full, "%s%s", file[0] == '/' ? "" : r->dir, file);
        if (strlen(file) < sizeof pb->source)
            snprintf(pb->source, sizeof pb->source, "%s", file);
    }
    if (r->dim == 3) {
        if (tn->type != YAML_SCALAR_NODE) {
            rd_fail(r, tn, tkey, "in 3D the upper surface is an ESRI ASCII grid on the terrain's grid: top: surface.asc");
            return;
        }
        lahar_heightmap top;
        if (lahar_heightmap_read_asc(full, &top, err, sizeof err) != 0) {
            rd_fail(r, tn, tkey, "%s (paths are relative to the case file's directory)", err);
            return;
        }
        if (lahar_heightmap_block(&r->terrain_hm, &top, full, r->terrain_radius + 0.5 * r->dx, pb, err, sizeof err) != 0)
            rd_fail(r, tn, tkey, "%s", err);
        lahar_heightmap_free(&top);
        return;
    }
    double(*t)[3] = NULL;
    int nt = 0;
    if (tn->type == YAML_SCALAR_NODE) {
        if (lahar_profile_read_csv(full, &t, &nt, err, sizeof err) != 0) {
            rd_fail(r, tn, tkey, "%s (paths are relative to the case file's directory)", err);
            return;
        }
    } else if (!(t = case_read_points(r, tn, tkey, 2, &nt))) {
        return;
    }
    double(*poly)[3] = NULL;
    int np = 0;
    /* no particle closer than the coupling's halo dx/2 to the terrain's surface (a particle
     * starting inside it gets the penalty's kick, which grows as 1/dt) */
    const double lift = r->terrain_radius + 0.5 * r->dx;
    if (lahar_profile_between((const double(*)[3])r->terrain_pts, r->terrain_npts, (const double(*)[3])t, nt, lift,
                              &poly, &np, err, sizeof err) != 0) {
        free(t);
        rd_fail(r, tn, tkey, "%s", err);
        return;
    }
    free(t);
    pb->kind = LAHAR_BLOCK_POLYGON;
    pb->vert = poly;
    pb->nvert = np;
    check_block_polygon(r, tn, tkey, pb);
}

/* phase: water (default) | soil, and for soil the model: soil material it is made of. */
static void read_block_phase(rmap *bm, lahar_particle_block *pb, const lahar_case *c)
{
    pb->phase = rd_key_choice(bm, "phase"); /* the table's order: water 0, soil 1 (SPH_SOIL_PHASE) */
    pb->material = -1;
    if (bm->r->failed)
        return;
    if (pb->phase == 0) {
        if (rmap_get(bm, "material"))
            rmap_fail(bm, "material", "water blocks take sph.density and sph.viscosity; a material is for phase: soil "
                      "(remove it, or add `phase: soil`)");
        return;
    }
    const char *name = rmap_str(bm, "material", 1, NULL, "sand   (a materials: entry with model: soil)");
    if (bm->r->failed)
        return;
    pb->material = lahar_case_find_material(c, name);
    if (pb->material < 0)
        rmap_fail(bm, "material", "unknown material '%s'; define it in materials: with model: soil", name);
    else if (c->materials[pb->material].model != LAHAR_CONTACT_SOIL)
        rmap_fail(bm, "material", "'%s' is a DEM material; a soil block needs a material with model: soil "
                  "(young, poisson, friction_angle, cohesion, dilatancy)", name);
    for (int j = 0; j < c->nblock - 1 && !bm->r->failed && pb->material >= 0; j++)
        if (c->blocks[j].phase == 1 && c->blocks[j].material != pb->material)
            rmap_fail(bm, "material", "'%s' differs from the soil of sph.blocks[%d] ('%s'); one soil material per "
                      "case is implemented", name, j, c->materials[c->blocks[j].material].name);
}

/* --- per-particle initial fields (libmatheval) ----------------------------------------------- */

/* Parse expression s in x, y, z (libmatheval: + - * / ^, sin, cos, tan, exp, log, sqrt, abs, ...,
 * constants pi, e). Returns the evaluator, or NULL with a reason in why. */
static void *expr_create(const char *s, char *why, size_t nwhy)
{
    char buf[LAHAR_EXPR_MAX];
    if (strlen(s) >= sizeof buf) {
        snprintf(why, nwhy, "longer than %d characters", LAHAR_EXPR_MAX - 1);
        return NULL;
    }
    snprintf(buf, sizeof buf, "%s", s);
    void *ev = evaluator_create(buf);
    if (!ev) {
        snprintf(why, nwhy, "cannot parse '%s' (libmatheval syntax: + - * / ^, sin, cos, exp, log, sqrt, ..., "
                 "constants pi and e, variables x, y, z)", s);
        return NULL;
    }
    char **names = NULL;
    int count = 0;
    evaluator_get_variables(ev, &names, &count);
    for (int k = 0; k < count; k++)
        if (strcmp(names[k], "x") != 0 && strcmp(names[k], "y") != 0 && strcmp(names[k], "z") != 0) {
            snprintf(why, nwhy, "unknown variable '%s' in '%s'; only x, y, z (the particle's position, m) and "
                     "the constants pi, e may appear; write other constants as numbers", names[k], s);
            evaluator_destroy(ev);
            return NULL;
        }
    return ev;
}

/* Check the expression of node n (key for messages) and copy it to out; also evaluates it at the
 * corners and the centre of the block's box: it must be finite there. */
static void check_block_expr(reader *r, yaml_node_t *n, const char *key, const char *s, const lahar_particle_block *pb,
                             char out[LAHAR_EXPR_MAX])
{
    char why[512];
    void *ev = expr_create(s, why, sizeof why);
    if (!ev) {
        rd_fail(r, n, key, "%s", why);
        return;
    }
    for (int k = 0; k < 9 && !r->failed; k++) {
        double x[3];
        for (int a = 0; a < 3; a++)
            x[a] = k == 8 ? 0.5 * (pb->lo[a] + pb->hi[a]) : ((k >> a) & 1 ? pb->hi[a] : pb->lo[a]);
        if (r->dim == 2)
            x[2] = 0.0;
        double v = evaluator_evaluate_x_y_z(ev, x[0], x[1], x[2]);
        if (!isfinite(v))
            rd_fail(r, n, key, "'%s' is not finite at (%g, %g, %g), a point of the block", s, x[0], x[1], x[2]);
    }
    evaluator_destroy(ev);
    snprintf(out, LAHAR_EXPR_MAX, "%s", s);
}

/* The initial-field datasets of an HDF5 file (initial: {file: F.h5}). */
static const char *const init_sets[5] = {"vx", "vy", "vz", "pressure", NULL}; /* NULL: for rd_closest_name */

/* H5Literate callback: the first link of the file's root that is not one of init_sets. */
static herr_t init_file_other_link(hid_t g, const char *name, const H5L_info_t *info, void *data)
{
    (void)g, (void)info;
    for (int k = 0; k < 4; k++)
        if (strcmp(name, init_sets[k]) == 0)
            return 0;
    snprintf(data, LAHAR_NAME_MAX, "%.*s", LAHAR_NAME_MAX - 1, name);
    return 1;
}

/* Open file `path` and, for k = 0..3 (vx, vy, vz, pressure), read dataset init_sets[k] after
 * checking it holds exactly n finite numbers, into out[k] (when out[k] is not NULL; else into a
 * buffer of its own, for the loader's check); found[k] = 1 when present. Anything else in the file
 * (a misspelt name) is refused, with the name it is closest to. 0, or -1 with a message naming the
 * file and the dataset. */
int case_init_file_read(const char *path, int64_t n, double *out[4], int found[4], char *err, size_t errlen)
{
    FILE *probe = lahar_fopen_input(path, "rb"); /* a missing file or a directory: errno says which */
    if (!probe) {
        snprintf(err, errlen, "%s: %s; give an HDF5 file with datasets vx, vy (, vz) and/or pressure (paths are "
                 "relative to the case file's directory)", path, strerror(errno));
        return -1;
    }
    fclose(probe);
    H5E_auto2_t fn;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &fn, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    int rc = 0;
    char other[LAHAR_NAME_MAX] = "";
    hid_t f = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (f < 0) {
        snprintf(err, errlen, "%s: not an HDF5 file; write the initial fields (e.g. with h5py) as "
                 "datasets vx, vy (, vz) and/or pressure", path);
        rc = -1;
    } else if (H5Literate(f, H5_INDEX_NAME, H5_ITER_NATIVE, NULL, init_file_other_link, other) > 0) {
        const char *near = NULL; /* a name it begins (p for pressure), else the closest one */
        for (int k = 0; k < 4 && !near; k++)
            if (strncmp(init_sets[k], other, strlen(other)) == 0)
                near = init_sets[k];
        if (!near)
            near = rd_closest_name(other, init_sets);
        snprintf(err, errlen, "%s: unknown dataset '%s'%s%s%s; the file may hold vx, vy, vz and pressure only", path,
                 other, near ? " (did you mean '" : "", near ? near : "", near ? "'?)" : "");
        rc = -1;
    }
    double *own = NULL;
    for (int k = 0; k < 4 && !rc; k++) {
        found[k] = H5Lexists(f, init_sets[k], H5P_DEFAULT) > 0;
        if (!found[k])
            continue;
        hid_t d = H5Dopen2(f, init_sets[k], H5P_DEFAULT), s = d >= 0 ? H5Dget_space(d) : -1;
        hid_t ty = d >= 0 ? H5Dget_type(d) : -1;
        H5T_class_t cls = ty >= 0 ? H5Tget_class(ty) : H5T_NO_CLASS;
        hssize_t m = s >= 0 ? H5Sget_simple_extent_npoints(s) : -1;
        double *buf = out[k];
        if (d < 0 || s < 0 || m < 0 || H5Sget_simple_extent_ndims(s) != 1 ||
            (cls != H5T_FLOAT && cls != H5T_INTEGER)) {
            snprintf(err, errlen, "%s: dataset '%s' is not a 1D array of numbers", path, init_sets[k]);
            rc = -1;
        } else if ((int64_t)m != n) {
            snprintf(err, errlen, "%s: dataset '%s' has %lld values, the block has %lld particles (one value per "
                     "particle, in lattice order)", path, init_sets[k], (long long)m, (long long)n);
            rc = -1;
        } else if (!buf && !(buf = own ? own : (own = malloc((size_t)(n > 0 ? n : 1) * sizeof *own)))) {
            snprintf(err, errlen, "%s: out of memory for %lld values", path, (long long)n);
            rc = -1;
        } else if (H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0) {
            snprintf(err, errlen, "%s: dataset '%s' cannot be read as numbers", path, init_sets[k]);
            rc = -1;
        }
        for (int64_t i = 0; i < n && !rc; i++)
            if (!isfinite(buf[i])) {
                snprintf(err, errlen, "%s: dataset '%s' value %lld is %g; every value must be a finite number", path,
                         init_sets[k], (long long)i, buf[i]);
                rc = -1;
            }
        if (ty >= 0)
            H5Tclose(ty);
        if (s >= 0)
            H5Sclose(s);
        if (d >= 0)
            H5Dclose(d);
    }
    free(own);
    if (f >= 0)
        H5Fclose(f);
    H5Eset_auto2(H5E_DEFAULT, fn, data);
    return rc;
}

int lahar_case_block_initial(const lahar_particle_block *pb, const double (*pts)[3], int64_t n, double (*v)[3],
                             double *p, int *has_p, char *err, size_t errlen)
{
    *has_p = pb->pexpr[0] != 0;
    if (pb->init_file[0]) { /* the loader has checked that no expression is given too */
        double *buf = malloc((size_t)(n > 0 ? n : 1) * 4 * sizeof *buf);
        if (!buf) {
            snprintf(err, errlen, "block '%s': out of memory", pb->name);
            return -1;
        }
        double *out[4] = {buf, buf + n, buf + 2 * n, buf + 3 * n};
        int found[4] = {0, 0, 0, 0};
        int rc = case_init_file_read(pb->init_file, n, out, found, err, errlen);
        for (int64_t i = 0; i < n && !rc; i++) { /* every value read is finite (case_init_file_read) */
            for (int a = 0; a < 3; a++)
                v[i][a] = found[a] ? out[a][i] : pb->v[a];
            if (found[3])
                p[i] = out[3][i];
        }
        *has_p = found[3];
        free(buf);
        return rc;
    }
    void *ev[4] = {NULL, NULL, NULL, NULL};
    const char *src[4] = {pb->vexpr[0], pb->vexpr[1], pb->vexpr[2], pb->pexpr};
    const char *what[4] = {"velocity[0]", "velocity[1]", "velocity[2]", "pressure"};
    int rc = 0;
    for (int k = 0; k < 4 && !rc; k++)
        if (src[k][0]) {
            char why[512];
            if (!(ev[k] = expr_create(src[k], why, sizeof why))) {
                snprintf(err, errlen, "block '%s': %s: %s", pb->name, what[k], why);
                rc = -1;
            }
        }
    for (int64_t i = 0; i < n && !rc; i++)
        for (int k = 0; k < 4 && !rc; k++) {
            double val = k < 3 ? pb->v[k] : 0.0;
            if (ev[k])
                val = evaluator_evaluate_x_y_z(ev[k], pts[i][0], pts[i][1], pts[i][2]);
            if (!isfinite(val)) {
                snprintf(err, errlen, "block '%s': %s '%s' is not finite at (%g, %g, %g)", pb->name, what[k], src[k],
                         pts[i][0], pts[i][1], pts[i][2]);
                rc = -1;
            } else if (k < 3 && v)
                v[i][k] = val;
            else if (k == 3 && p && ev[3])
                p[i] = val;
        }
    for (int k = 0; k < 4; k++)
        if (ev[k])
            evaluator_destroy(ev[k]);
    return rc;
}

/* velocity: [numbers or expressions] and pressure: (number or expression) of block pb, checked once
 * the block's box is known. */
static void read_block_fields(reader *r, rmap *bm, lahar_particle_block *pb)
{
    const int dim = r->dim;
    yaml_node_t *vn = rmap_get(bm, "velocity"), *pn = rmap_get(bm, "pressure");
    char key[KEY_MAX];
    if (vn && vn->type == YAML_SEQUENCE_NODE && rd_seq_len(vn) == dim) {
        for (int a = 0; a < dim && !r->failed; a++) {
            yaml_node_t *it = rd_seq_item(r, vn, a);
            snprintf(key, sizeof key, "%.*s.velocity[%d]", KEY_MAX - 32, bm->prefix, a & 3);
            if (!it || it->type != YAML_SCALAR_NODE) {
                rd_fail(r, it ? it : vn, key, "expected a number or an expression in x, y, z, got %s",
                        it ? rd_node_kind(it) : "nothing");
                return;
            }
            const char *s = rd_scalar(it);
            char *end = NULL;
            double v = strtod(s, &end);
            while (end && (*end == ' ' || *end == '\t'))
                end++;
            if (end != s && end && *end == '\0' && isfinite(v))
                pb->v[a] = v;
            else
                check_block_expr(r, it, key, s, pb, pb->vexpr[a]);
        }
    } else if (vn)
        rmap_vec(bm, "velocity", dim, pb->v, 0, ""); /* its message */
    yaml_node_t *in = rmap_get(bm, "initial");
    if (in && !r->failed) {
        static const char *const ikeys[] = {"file", NULL};
        rd_key_join(bm->prefix, "initial", key);
        rmap im;
        if (rmap_open(r, in, key, &im) != 0)
            return;
        rmap_check_keys(&im, ikeys);
        const char *file = rmap_str(&im, "file", 1, NULL, "initial.h5");
        if (r->failed)
            return;
        char full[2048];
        if (file[0] == '/')
            snprintf(full, sizeof full, "%s", file);
        else
            snprintf(full, sizeof full, "%s%s", r->dir, file);
        if (strlen(full) >= sizeof pb->init_file) {
            rmap_fail(&im, "file", "path longer than %d characters", (int)sizeof pb->init_file - 1);
            return;
        }
        if (vn || pn) {
            rmap_fail(bm, "initial", "give the initial fields either as velocity:/pressure: keys or in the file, "
                      "not both");
            return;
        }
        memcpy(pb->init_file, full, strlen(full) + 1); /* fits: checked above */
    }
    if (pn && !r->failed) {
        rd_key_join(bm->prefix, "pressure", key);
        if (pn->type != YAML_SCALAR_NODE || !rd_scalar(pn)[0])
            rd_fail(r, pn, key, "expected a number or an expression in x, y, z (Pa), got %s",
                    pn->type == YAML_SCALAR_NODE ? "an empty value" : rd_node_kind(pn));
        else if (pb->phase != 0)
            rd_fail(r, pn, key, "sets the initial pressure of water; block '%s' is soil (its stress starts at 0)",
                    pb->name);
        else
            check_block_expr(r, pn, key, rd_scalar(pn), pb, pb->pexpr);
    }
}

static void read_block_geometry(reader *r, yaml_node_t *n, int i, lahar_case *c, rmap *bm);

void case_read_block(reader *r, yaml_node_t *n, int i, lahar_case *c)
{
    rmap bm;
    read_block_geometry(r, n, i, c, &bm);
    if (!r->failed)
        read_block_fields(r, &bm, &c->blocks[i]);
}

static void read_block_geometry(reader *r, yaml_node_t *n, int i, lahar_case *c, rmap *bmo)
{
    static const char *const boxkeys[] = {"lo", "hi", NULL};
    const int dim = r->dim;
    lahar_particle_block *pb = &c->blocks[i];
    char prefix[KEY_MAX], def[LAHAR_NAME_MAX];
    snprintf(prefix, sizeof prefix, "sph.blocks[%d]", i);
    snprintf(def, sizeof def, "block%d", i);
    rmap xm;
    if (rmap_open(r, n, prefix, bmo) != 0)
        return;
    rmap_section(bmo, "sph.blocks[]");
    rmap_name(bmo, "name", 0, def, pb->name);
    for (int j = 0; j < i && !r->failed; j++)
        if (strcmp(c->blocks[j].name, pb->name) == 0)
            rmap_fail(bmo, "name", "'%s' is already the name of sph.blocks[%d]; block names must be unique", pb->name, j);
    read_block_phase(bmo, pb, c);
    yaml_node_t *bx = rmap_get(bmo, "box"), *pg = rmap_get(bmo, "polygon"), *st = rmap_get(bmo, "stl");
    yaml_node_t *bw = rmap_get(bmo, "between");
    if (r->failed)
        return;
    if (!!bx + !!pg + !!st + !!bw != 1) {
        if (!bx && !pg && !st && !bw)
            rmap_missing(bmo, "box", dim == 3 ? "{lo: [0, 0, 0], hi: [0.1, 0.1, 0.1]}  (or polygon: / stl:)"
                                              : "{lo: [0, 0], hi: [0.1, 0.1]}  (or polygon: [[x, y], ...])");
        else
            rd_fail(r, n, prefix, "give exactly one of box, polygon (2D), stl (3D) or between per block");
        return;
    }
    if (bw) {
        read_block_between(r, bw, prefix, pb);
        return;
    }
    if (pg) {
        read_block_polygon(r, pg, prefix, pb);
        return;
    }
    if (st) {
        read_block_stl(r, st, prefix, pb);
        return;
    }
    char bp[KEY_MAX];
    rd_key_join(prefix, "box", bp);
    if (rmap_open(r, bx, bp, &xm) != 0)
        return;
    rmap_check_keys(&xm, boxkeys);
    pb->kind = LAHAR_BLOCK_BOX;
    rmap_vec(&xm, "lo", dim, pb->lo, 1, dim == 3 ? "[0, 0, 0]" : "[0, 0]");
    rmap_vec(&xm, "hi", dim, pb->hi, 1, dim == 3 ? "[0.1, 0.1, 0.1]" : "[0.1, 0.1]");
    for (int k = 0; k < dim && !r->failed; k++)
        if (!(pb->hi[k] > pb->lo[k]))
            rmap_fail(&xm, "hi", "must be > lo in every component (component %d: %g <= %g)", k, pb->hi[k], pb->lo[k]);
}
