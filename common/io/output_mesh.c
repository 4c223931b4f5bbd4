/* Display meshes of sphero-polyhedra for the XDMF output (declared in output.h). Only for
 * viewing: the physics uses the exact swept shape in geometry.c. Built once per body at setup,
 * so the growable arrays here never run inside a time step. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "geometry.h"
#include "output.h"
#include "vec.h"

#define MESH_ICO_LEVEL 2     /* icosphere subdivisions: 162 vertices, 320 triangles */
#define MESH_TUBE_SIDES 12   /* sides of the tube drawn around a rod edge */
#define MESH_CIRCLE_SEGS 48  /* line segments of a full circle in 2D */

typedef struct {
    lahar_display_mesh *m;
    int vcap, ccap;
    int failed;
} mesh_builder;

static int mesh_add_vertex(mesh_builder *b, vec3 p)
{
    lahar_display_mesh *m = b->m;
    if (m->nvert == b->vcap) {
        int cap = b->vcap ? 2 * b->vcap : 64;
        void *nv = realloc(m->v, (size_t)cap * sizeof m->v[0]);
        if (!nv) {
            b->failed = 1;
            return 0;
        }
        m->v = nv;
        b->vcap = cap;
    }
    v3_store(p, m->v[m->nvert]);
    return m->nvert++;
}

static void mesh_add_cell(mesh_builder *b, int i0, int i1, int i2)
{
    lahar_display_mesh *m = b->m;
    if (m->ncell == b->ccap) {
        int cap = b->ccap ? 2 * b->ccap : 64;
        void *nc = realloc(m->cell, (size_t)cap * (size_t)m->nodes_per_cell * sizeof m->cell[0]);
        if (!nc) {
            b->failed = 1;
            return;
        }
        m->cell = nc;
        b->ccap = cap;
    }
    int32_t *c = m->cell + (size_t)m->ncell * (size_t)m->nodes_per_cell;
    c[0] = i0;
    c[1] = i1;
    if (m->nodes_per_cell == 3)
        c[2] = i2;
    m->ncell++;
}

static vec3 mesh_vertex(const lahar_display_mesh *m, int i) { return v3_load(m->v[i]); }

/* Triangle (i0, i1, i2) oriented so that its normal points along `outward`. */
static void mesh_add_triangle_facing(mesh_builder *b, int i0, int i1, int i2, vec3 outward)
{
    vec3 a = mesh_vertex(b->m, i0), c1 = mesh_vertex(b->m, i1), c2 = mesh_vertex(b->m, i2);
    vec3 nrm = v3_cross(v3_sub(c1, a), v3_sub(c2, a));
    if (v3_dot(nrm, outward) < 0.0)
        mesh_add_cell(b, i0, i2, i1);
    else
        mesh_add_cell(b, i0, i1, i2);
}

/* Unit icosphere: subdivided icosahedron, vertices pushed onto the unit sphere. */
typedef struct {
    int nv, nt;
    vec3 v[642];
    int t[1280][3];
} icosphere;

static int ico_midpoint(icosphere *s, int a, int b)
{
    vec3 p = v3_normalize(v3_scale(v3_add(s->v[a], s->v[b]), 0.5));
    for (int i = 0; i < s->nv; i++) /* setup only, a few hundred vertices */
        if (v3_norm2(v3_sub(s->v[i], p)) < 1e-20)
            return i;
    s->v[s->nv] = p;
    return s->nv++;
}

static void icosphere_make(icosphere *s, int level)
{
    const double g = (1.0 + sqrt(5.0)) / 2.0;
    const double base[12][3] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                                {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    static const int tri[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                   {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                   {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    s->nv = 12;
    for (int i = 0; i < 12; i++)
        s->v[i] = v3_normalize(v3_load(base[i]));
    s->nt = 20;
    memcpy(s->t, tri, sizeof tri);
    for (int l = 0; l < level; l++) {
        int (*old)[3] = malloc((size_t)s->nt * sizeof *old);
        if (!old)
            return;
        memcpy(old, s->t, (size_t)s->nt * sizeof *old);
        int nt = s->nt;
        s->nt = 0;
        for (int k = 0; k < nt; k++) {
            int a = old[k][0], b = old[k][1], c = old[k][2];
            int ab = ico_midpoint(s, a, b), bc = ico_midpoint(s, b, c), ca = ico_midpoint(s, c, a);
            int nt4[4][3] = {{a, ab, ca}, {b, bc, ab}, {c, ca, bc}, {ab, bc, ca}};
            memcpy(s->t[s->nt], nt4, sizeof nt4);
            s->nt += 4;
        }
        free(old);
    }
}

static void mesh_add_sphere(mesh_builder *b, const icosphere *ico, vec3 c, double r)
{
    int base = b->m->nvert;
    for (int i = 0; i < ico->nv; i++)
        mesh_add_vertex(b, v3_axpy(r, ico->v[i], c));
    for (int k = 0; k < ico->nt; k++)
        mesh_add_triangle_facing(b, base + ico->t[k][0], base + ico->t[k][1], base + ico->t[k][2],
                                 v3_sub(v3_load(b->m->v[base + ico->t[k][0]]), c));
}

static void mesh_add_tube(mesh_builder *b, vec3 p0, vec3 p1, double r)
{
    vec3 ax = v3_normalize(v3_sub(p1, p0));
    if (v3_norm2(ax) == 0.0)
        return;
    vec3 helper = fabs(ax.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
    vec3 u = v3_normalize(v3_cross(ax, helper)), w = v3_cross(ax, u);
    int base = b->m->nvert;
    for (int k = 0; k < MESH_TUBE_SIDES; k++) {
        double a = 2.0 * M_PI * k / MESH_TUBE_SIDES;
        vec3 d = v3_add(v3_scale(u, r * cos(a)), v3_scale(w, r * sin(a)));
        mesh_add_vertex(b, v3_add(p0, d));
        mesh_add_vertex(b, v3_add(p1, d));
    }
    for (int k = 0; k < MESH_TUBE_SIDES; k++) {
        int k1 = (k + 1) % MESH_TUBE_SIDES;
        int a0 = base + 2 * k, a1 = a0 + 1, b0 = base + 2 * k1, b1 = b0 + 1;
        vec3 out = v3_sub(mesh_vertex(b->m, a0), p0);
        mesh_add_triangle_facing(b, a0, b0, b1, out);
        mesh_add_triangle_facing(b, a0, b1, a1, out);
    }
}

/* Directed edge (a -> b) of face f, starting at position `local` of the face. */
typedef struct {
    int a, b, f, local;
} mesh_dedge;

static int dedge_cmp(const void *x, const void *y)
{
    const mesh_dedge *p = x, *q = y;
    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    if (p->b != q->b)
        return p->b < q->b ? -1 : 1;
    return 0;
}

static const mesh_dedge *dedge_find(const mesh_dedge *e, int ne, int a, int b)
{
    mesh_dedge key = {a, b, 0, 0};
    return bsearch(&key, e, (size_t)ne, sizeof *e, dedge_cmp);
}

/* 3D polyhedron: offset faces, bevel quads between adjacent faces, corner fans. */
static int mesh_polyhedron(mesh_builder *b, const lahar_shape *s)
{
    int nfv = s->face_start[s->nf];
    int *offset_index = malloc((size_t)nfv * sizeof *offset_index); /* per face corner */
    vec3 *normal = malloc((size_t)s->nf * sizeof *normal);
    mesh_dedge *de = malloc((size_t)nfv * sizeof *de);
    int *first = malloc((size_t)s->nv * sizeof *first); /* a face corner at each vertex */
    int *corner = malloc((size_t)(nfv + 1) * sizeof *corner);
    int *corner_face = malloc((size_t)(nfv + 1) * sizeof *corner_face); /* face of each corner */
    if (!offset_index || !normal || !de || !first || !corner || !corner_face) {
        free(offset_index), free(normal), free(de), free(first), free(corner), free(corner_face);
        return -1;
    }
    for (int f = 0; f < s->nf; f++)
        for (int k = s->face_start[f]; k < s->face_start[f + 1]; k++)
            corner_face[k] = f;
    const double r = s->radius;
    for (int i = 0; i < s->nv; i++)
        first[i] = -1;
    for (int f = 0; f < s->nf; f++) {
        int f0 = s->face_start[f], k = s->face_start[f + 1] - f0;
        normal[f] = geom_face_normal(s, f);
        for (int i = 0; i < k; i++) {
            int vi = s->face_v[f0 + i];
            offset_index[f0 + i] = mesh_add_vertex(b, v3_axpy(r, normal[f], v3_load(s->v[vi])));
            de[f0 + i] = (mesh_dedge){vi, s->face_v[f0 + (i + 1) % k], f, i};
            if (first[vi] < 0)
                first[vi] = f0 + i;
        }
        for (int i = 1; i + 1 < k; i++)
            mesh_add_triangle_facing(b, offset_index[f0], offset_index[f0 + i], offset_index[f0 + i + 1], normal[f]);
        if (s->nf == 1) { /* a lone plate: the sweep makes a slab, show its back too */
            int back0 = b->m->nvert;
            for (int i = 0; i < k; i++)
                mesh_add_vertex(b, v3_axpy(-r, normal[f], v3_load(s->v[s->face_v[f0 + i]])));
            for (int i = 1; i + 1 < k; i++)
                mesh_add_triangle_facing(b, back0, back0 + i, back0 + i + 1, v3_neg(normal[f]));
        }
    }
    qsort(de, (size_t)nfv, sizeof *de, dedge_cmp);
    if (r > 0.0) {
        /* bevels: each shared edge once (a < b), between the offset copies in both faces */
        for (int k = 0; k < nfv; k++) {
            const mesh_dedge *e = &de[k];
            if (e->a >= e->b)
                continue;
            const mesh_dedge *t = dedge_find(de, nfv, e->b, e->a);
            if (!t)
                continue;
            int fs = s->face_start[e->f], fn = s->face_start[e->f + 1] - fs;
            int ts = s->face_start[t->f], tn = s->face_start[t->f + 1] - ts;
            int af = offset_index[fs + e->local], bf = offset_index[fs + (e->local + 1) % fn];
            int bg = offset_index[ts + t->local], ag = offset_index[ts + (t->local + 1) % tn];
            vec3 out = v3_add(normal[e->f], normal[t->f]);
            mesh_add_triangle_facing(b, af, bf, bg, out);
            mesh_add_triangle_facing(b, af, bg, ag, out);
        }
        /* corners: walk the faces around each vertex through the twin edges */
        for (int vi = 0; vi < s->nv; vi++) {
            if (first[vi] < 0)
                continue;
            int nc = 0, closed = 0;
            int f = -1, cur = first[vi];
            vec3 out = v3(0, 0, 0);
            for (int guard = 0; guard <= nfv; guard++) {
                /* cur: corner index (face_start[f] + i) of vertex vi in face f */
                f = corner_face[cur];
                int fs = s->face_start[f], fn = s->face_start[f + 1] - fs, i = cur - fs;
                corner[nc++] = offset_index[cur];
                out = v3_add(out, normal[f]);
                int prev = s->face_v[fs + (i + fn - 1) % fn];
                const mesh_dedge *t = dedge_find(de, nfv, vi, prev); /* twin of (prev -> vi) */
                if (!t)
                    break;
                int next = s->face_start[t->f] + t->local;
                if (next == first[vi]) {
                    closed = 1;
                    break;
                }
                cur = next;
            }
            if (closed && nc >= 3)
                for (int k = 1; k + 1 < nc; k++)
                    mesh_add_triangle_facing(b, corner[0], corner[k], corner[k + 1], out);
        }
    }
    free(offset_index), free(normal), free(de), free(first), free(corner), free(corner_face);
    return 0;
}

typedef struct {
    double ang;
    int i;
} angle_index;
static int angle_cmp(const void *x, const void *y)
{
    const angle_index *p = x, *q = y;
    return p->ang < q->ang ? -1 : (p->ang > q->ang ? 1 : (p->i - q->i));
}

static void mesh_add_arc(mesh_builder *b, vec3 c, double r, double a0, double a1, int *last)
{
    int nseg = (int)ceil((a1 - a0) / (2.0 * M_PI / MESH_CIRCLE_SEGS) - 1e-9);
    for (int k = 1; k <= nseg; k++) {
        double a = a0 + (a1 - a0) * k / nseg;
        int idx = mesh_add_vertex(b, v3(c.x + r * cos(a), c.y + r * sin(a), 0.0));
        if (*last >= 0)
            mesh_add_cell(b, *last, idx, 0);
        *last = idx;
    }
}

/* 2D convex body: the rounded outline (edges offset by R joined by arcs about the vertices);
 * one vertex gives a circle, two a capsule. */
static int mesh_outline_convex(mesh_builder *b, const lahar_shape *s)
{
    angle_index *order = malloc((size_t)s->nv * sizeof *order);
    if (!order)
        return -1;
    vec3 cen = v3(0, 0, 0);
    for (int i = 0; i < s->nv; i++)
        cen = v3_add(cen, v3_load(s->v[i]));
    cen = v3_scale(cen, 1.0 / s->nv);
    int k = 0;
    for (int i = 0; i < s->nv; i++) {
        int dup = 0;
        for (int j = 0; j < k; j++)
            if (s->v[order[j].i][0] == s->v[i][0] && s->v[order[j].i][1] == s->v[i][1])
                dup = 1;
        if (!dup)
            order[k++] = (angle_index){atan2(s->v[i][1] - cen.y, s->v[i][0] - cen.x), i};
    }
    qsort(order, (size_t)k, sizeof *order, angle_cmp);
    const double r = s->radius;
    int start = b->m->nvert, last = -1;
    if (k == 1) {
        vec3 c = v3_load(s->v[order[0].i]);
        for (int j = 0; j < MESH_CIRCLE_SEGS; j++) {
            double a = 2.0 * M_PI * j / MESH_CIRCLE_SEGS;
            int idx = mesh_add_vertex(b, v3(c.x + r * cos(a), c.y + r * sin(a), 0.0));
            if (last >= 0)
                mesh_add_cell(b, last, idx, 0);
            last = idx;
        }
    } else {
        for (int j = 0; j < k; j++) {
            vec3 p = v3_load(s->v[order[j].i]);
            vec3 pp = v3_load(s->v[order[(j + k - 1) % k].i]), pn = v3_load(s->v[order[(j + 1) % k].i]);
            vec3 din = v3_sub(p, pp), dout = v3_sub(pn, p);
            /* a counter-clockwise edge with direction d has the outward normal (d.y, -d.x) */
            double a_in = atan2(-din.x, din.y), a_out = atan2(-dout.x, dout.y);
            while (a_out < a_in)
                a_out += 2.0 * M_PI;
            int idx = mesh_add_vertex(b, v3(p.x + r * cos(a_in), p.y + r * sin(a_in), 0.0));
            if (last >= 0)
                mesh_add_cell(b, last, idx, 0);
            last = idx;
            if (r > 0.0 && a_out > a_in)
                mesh_add_arc(b, p, r, a_in, a_out, &last);
        }
    }
    mesh_add_cell(b, last, start, 0);
    free(order);
    return 0;
}

/* 2D open or non-convex body (segments, polylines, terrain): each edge as a thin quad outline
 * of half-width R (a single line when R = 0); lone vertices as circles. */
static int mesh_outline_edges(mesh_builder *b, const lahar_shape *s)
{
    const double r = s->radius;
    for (int k = 0; k < s->ne; k++) {
        vec3 p0 = v3_load(s->v[s->e[k][0]]), p1 = v3_load(s->v[s->e[k][1]]);
        vec3 d = v3_normalize(v3_sub(p1, p0));
        vec3 nrm = v3(d.y, -d.x, 0.0);
        if (r <= 0.0) {
            int i0 = mesh_add_vertex(b, p0), i1 = mesh_add_vertex(b, p1);
            mesh_add_cell(b, i0, i1, 0);
            continue;
        }
        int q0 = mesh_add_vertex(b, v3_axpy(r, nrm, p0)), q1 = mesh_add_vertex(b, v3_axpy(r, nrm, p1));
        int q2 = mesh_add_vertex(b, v3_axpy(-r, nrm, p1)), q3 = mesh_add_vertex(b, v3_axpy(-r, nrm, p0));
        mesh_add_cell(b, q0, q1, 0);
        mesh_add_cell(b, q1, q2, 0);
        mesh_add_cell(b, q2, q3, 0);
        mesh_add_cell(b, q3, q0, 0);
    }
    if (s->ne == 0) /* a non-convex cloud of vertices: a circle for each */
        for (int i = 0; i < s->nv; i++) {
            lahar_shape one = {.nv = 1, .v = &s->v[i], .radius = r};
            if (mesh_outline_convex(b, &one))
                return -1;
        }
    return 0;
}

int lahar_display_mesh_build(const lahar_shape *s, int dim, int convex, lahar_display_mesh *m)
{
    memset(m, 0, sizeof *m);
    m->nodes_per_cell = dim == 2 ? 2 : 3;
    mesh_builder b = {.m = m};
    int rc = 0;
    if (s->nv <= 0) {
        rc = 0;
    } else if (dim == 2) {
        /* a closed convex polygon (or a disc / segment) gets its rounded outline; open chains
         * (polylines, terrain) and non-convex bodies get a thin quad per edge */
        rc = (s->nv <= 2 || (convex && s->ne == s->nv)) ? mesh_outline_convex(&b, s) : mesh_outline_edges(&b, s);
    } else if (s->nf > 0) {
        rc = mesh_polyhedron(&b, s);
    } else {
        icosphere *ico = malloc(sizeof *ico);
        if (!ico)
            return -1;
        icosphere_make(ico, MESH_ICO_LEVEL);
        for (int i = 0; i < s->nv; i++)
            mesh_add_sphere(&b, ico, v3_load(s->v[i]), s->radius);
        for (int k = 0; k < s->ne; k++)
            mesh_add_tube(&b, v3_load(s->v[s->e[k][0]]), v3_load(s->v[s->e[k][1]]), s->radius);
        free(ico);
    }
    if (rc || b.failed) {
        lahar_display_mesh_free(m);
        return -1;
    }
    return 0;
}

void lahar_display_mesh_free(lahar_display_mesh *m)
{
    free(m->v);
    free(m->cell);
    m->v = NULL;
    m->cell = NULL;
    m->nvert = m->ncell = 0;
}
