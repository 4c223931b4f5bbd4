/* The LAMMPS engine's create: the refusals (everything LAMMPS could refuse, checked before a
 * single command: Debian's LAMMPS ends the process on an error), then the LAMMPS instance built
 * from C calls. The engine and its conventions: lammps_engine.c and README.md. */
#include "lammps_internal.h"
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <lammps/library.h>
#include "vec.h"

/* ---- setup -------------------------------------------------------------------------------------- */

/* Largest stable substep: the rule every engine uses (dem_stable_dt, dem_contact.h), on the
 * scene's bodies (walls with their sweep radius, as spheropoly), so that both engines take the
 * same substeps. */
static double stable_dt_of(const lahar_case *c, const dem_pair_law *laws, char *err, size_t errlen)
{
    double safety = c->dem_dt_safety > 0.0 ? c->dem_dt_safety : 0.02;
    vec3 lo = v3(DBL_MAX, DBL_MAX, DBL_MAX), hi = v3(-DBL_MAX, -DBL_MAX, -DBL_MAX);
    double vmax = 0.0;
    dem_step_body *sb = malloc((size_t)(c->nbody > 0 ? c->nbody : 1) * sizeof *sb);
    if (!sb) {
        snprintf(err, errlen, "lammps engine: out of memory");
        return 0.0;
    }
    for (int i = 0; i < c->nbody; i++) {
        const lahar_body *b = &c->bodies[i];
        for (int k = 0; k < b->shape.nv; k++) {
            vec3 w = v3_add(v3_load(b->x), q_rotate(q_load(b->q), v3_load(b->shape.v[k])));
            lo = v3(fmin(lo.x, w.x), fmin(lo.y, w.y), fmin(lo.z, w.z));
            hi = v3(fmax(hi.x, w.x), fmax(hi.y, w.y), fmax(hi.z, w.z));
        }
        /* a sphere's bounding radius about its centre is its radius */
        double v = v3_norm(v3_load(b->v)) + v3_norm(v3_load(b->w)) * b->shape.radius;
        if (v > vmax) vmax = v;
        sb[i] = (dem_step_body){.material = b->material, .free = b->motion == LAHAR_MOTION_FREE,
                                .radius = b->shape.radius, .mass = b->mass};
    }
    double extent = c->nbody > 0 ? v3_norm(v3_sub(hi, lo)) : 0.0;
    double dt = dem_stable_dt(sb, c->nbody, laws, c->nmaterial, dem_impact_speed(vmax, v3_norm(v3_load(c->gravity)), extent),
                              safety, c->dt_max);
    free(sb);
    return dt;
}

void lmp_destroy(lahar_dem_engine *e)
{
    if (!e) return;
    if (e->lmp) lammps_close(e->lmp);
    free(e->free_of_body);
    free(e->body_of_free);
    free(e->type_of_free);
    free(e->mass);
    free(e->radius);
    free(e->inertia);
    free(e->walls);
    free(e->st);
    free(e->load_f);
    free(e->load_t);
    free(e->acc_f);
    free(e->acc_t);
    free(e->rep_f);
    free(e->rep_t);
    free(e->last_f);
    free(e->last_t);
    free(e->wacc_f);
    free(e->wacc_t);
    free(e->wload_f);
    free(e->wload_t);
    free(e->wrep_f);
    free(e->wrep_t);
    free(e->wfix_id);
    free(e->wfix_wall);
    free(e->refix_id);
    free(e->refix_cmd);
    free(e->ncontact_body);
    free(e);
}

/* A fixed body LAMMPS can hold: a plane (3D, one flat face) or a segment (2D, one edge), as the
 * infinite plane through it on the side of the free bodies. */
static int make_wall(const lahar_case *c, int i, lmp_wall *w, char *err, size_t errlen)
{
    const lahar_body *b = &c->bodies[i];
    const lahar_shape *s = &b->shape;
    vec3 p0, n;
    if (c->dim == 3 && s->nf == 1 && s->nv >= 3) {
        int f0 = s->face_start[0];
        vec3 a = v3_load(s->v[s->face_v[f0]]), bb = v3_load(s->v[s->face_v[f0 + 1]]);
        vec3 cc = v3_load(s->v[s->face_v[f0 + 2]]);
        n = v3_cross(v3_sub(bb, a), v3_sub(cc, a));
        p0 = a;
        for (int k = 0; k < s->nv; k++)
            if (fabs(v3_dot(v3_sub(v3_load(s->v[k]), a), v3_normalize(n))) > 1e-9 * (1.0 + v3_norm(v3_load(s->v[k])))) {
                n = v3(0, 0, 0);
                break;
            }
    } else if (c->dim == 2 && s->nv == 2 && s->ne == 1 && s->nf == 0) {
        vec3 a = v3_load(s->v[0]), d = v3_sub(v3_load(s->v[1]), a);
        n = v3(-d.y, d.x, 0.0);
        p0 = a;
    } else {
        n = v3(0, 0, 0);
        p0 = v3(0, 0, 0);
    }
    if (!(v3_norm(n) > 0.0)) {
        snprintf(err, errlen,
                 "%s: body '%s': the lammps engine holds only fixed planes (3D, shape: plane) and segments (2D, shape: "
                 "segment) as walls, not this %d-vertex %d-face shape; use dem.engine: spheropoly",
                 c->path, b->name, s->nv, s->nf);
        return -1;
    }
    n = v3_normalize(n);
    /* the side of the free bodies */
    int pos = 0, neg = 0;
    for (int j = 0; j < c->nbody; j++) {
        if (c->bodies[j].motion != LAHAR_MOTION_FREE) continue;
        double d = v3_dot(v3_sub(v3_load(c->bodies[j].x), p0), n);
        if (d > 0.0) pos++;
        else if (d < 0.0) neg++;
    }
    if (pos && neg) {
        snprintf(err, errlen,
                 "%s: body '%s': free bodies lie on both sides of this wall; the lammps engine makes a wall an infinite "
                 "one-sided plane: split the scene or use dem.engine: spheropoly",
                 c->path, b->name);
        return -1;
    }
    if (neg) n = v3_neg(n);
    w->body = i;
    w->material = b->material;
    w->radius = s->radius;
    for (int a = 0; a < 3; a++) w->c[a] = b->x[a];
    v3_store(v3_axpy(s->radius, n, p0), w->p);
    v3_store(n, w->n);
    return 0;
}

/* ---- create: the refusals, before LAMMPS ------------------------------------------------------- */

/* What create works with and the engine does not keep: the contact law of every pair of materials
 * and the classes behind the atom types. Freed on every way out of lmp_build. */
typedef struct {
    dem_pair_law *laws; /* [a * nmaterial + b] */
    int *tmat;          /* per atom type (0-based): its material */
    double *tmass;      /* per atom type: the mass of its bodies (linear law; c_n needs it), 0 (Hertz) */
} lmp_setup;

static void setup_free(lmp_setup *su)
{
    free(su->laws);
    free(su->tmat);
    free(su->tmass);
}

static int lmp_oom(char *err, size_t errlen)
{
    snprintf(err, errlen, "lammps engine: out of memory");
    return -1;
}

static const dem_pair_law *type_law(const lahar_case *c, const lmp_setup *su, int t, int u)
{
    return &su->laws[su->tmat[t] * c->nmaterial + su->tmat[u]];
}

static const dem_pair_law *wall_law(const lahar_case *c, const lmp_setup *su, int t, const lmp_wall *wl)
{
    return &su->laws[su->tmat[t] * c->nmaterial + wl->material];
}

/* m* of two atom types for the linear law's c_n (Hertz types carry mass 0: LAMMPS computes m*) */
static double type_mstar(const lmp_setup *su, int t, int u)
{
    const double *tmass = su->tmass;
    return tmass[t] > 0.0 && tmass[u] > 0.0 ? tmass[t] * tmass[u] / (tmass[t] + tmass[u]) : 0.0;
}

/* What the engine cannot run whatever the bodies are. */
static int check_case_sections(const lahar_case *c, char *err, size_t errlen)
{
    if (c->checkpoint_interval > 0.0 || c->resume) {
        snprintf(err, errlen,
                 "%s: checkpoint: the lammps engine has no bitwise checkpoint/restart (lahar resume could not "
                 "continue the run bit for bit): remove the checkpoint: section or use dem.engine: spheropoly",
                 c->path);
        return -1;
    }
    if (c->dim != 2 && c->dim != 3) {
        snprintf(err, errlen, "%s: dimensions %d", c->path, c->dim);
        return -1;
    }
    return 0;
}

/* The per-body arrays are sized for every body: how many are free and how many are walls is known
 * only once take_body has seen them all. */
static int alloc_engine(lahar_dem_engine *e, const lahar_case *c, lmp_setup *su, char *err, size_t errlen)
{
    e->dim = c->dim;
    e->nbody = c->nbody;
    e->max_overlap = c->stability.max_overlap > 0.0 ? c->stability.max_overlap : 0.5;
    size_t nb = (size_t)(c->nbody > 0 ? c->nbody : 1);
    e->free_of_body = malloc(nb * sizeof(int));
    e->body_of_free = malloc(nb * sizeof(int));
    e->type_of_free = malloc(nb * sizeof(int));
    e->mass = malloc(nb * sizeof(double));
    e->radius = malloc(nb * sizeof(double));
    e->inertia = malloc(nb * sizeof(double));
    e->walls = calloc(nb, sizeof(lmp_wall));
    e->st = calloc(nb, sizeof(lahar_body_state));
    e->load_f = calloc(nb, sizeof *e->load_f);
    e->load_t = calloc(nb, sizeof *e->load_t);
    e->acc_f = calloc(nb, sizeof *e->acc_f);
    e->acc_t = calloc(nb, sizeof *e->acc_t);
    e->rep_f = calloc(nb, sizeof *e->rep_f);
    e->rep_t = calloc(nb, sizeof *e->rep_t);
    e->last_f = calloc(nb, sizeof *e->last_f);
    e->wacc_f = calloc(nb, sizeof *e->wacc_f);
    e->wacc_t = calloc(nb, sizeof *e->wacc_t);
    e->wload_f = calloc(nb, sizeof *e->wload_f);
    e->wload_t = calloc(nb, sizeof *e->wload_t);
    e->wrep_f = calloc(nb, sizeof *e->wrep_f);
    e->wrep_t = calloc(nb, sizeof *e->wrep_t);
    e->last_t = calloc(nb, sizeof *e->last_t);
    e->ncontact_body = calloc(nb, sizeof(int));
    int nm = c->nmaterial > 0 ? c->nmaterial : 1;
    su->laws = calloc((size_t)nm * (size_t)nm, sizeof *su->laws);
    if (!e->free_of_body || !e->body_of_free || !e->type_of_free || !e->mass || !e->radius || !e->inertia ||
        !e->walls || !e->st || !e->load_f || !e->load_t || !e->acc_f || !e->acc_t || !e->rep_f || !e->rep_t || !e->last_f || !e->last_t ||
        !e->wacc_f || !e->wacc_t || !e->wload_f || !e->wload_t || !e->wrep_f || !e->wrep_t ||
        !e->ncontact_body || !su->laws)
        return lmp_oom(err, errlen);
    return 0;
}

/* The laws of dem_contact.c, combined as spheropoly combines them, so both engines agree. */
static int make_pair_laws(const lahar_case *c, dem_pair_law *laws, char *err, size_t errlen)
{
    for (int a = 0; a < c->nmaterial; a++)
        for (int b = 0; b < c->nmaterial; b++)
            if (dem_pair_law_make(&c->materials[a], &c->materials[b], &laws[a * c->nmaterial + b], err, errlen) != 0)
                return -1;
    return 0;
}

/* Body i becomes a wall (fixed) or a free sphere/disc; anything else is refused by its name, since
 * LAMMPS itself would end the process instead of answering. */
static int take_body(lahar_dem_engine *e, const lahar_case *c, int i, char *err, size_t errlen)
{
    const lahar_body *b = &c->bodies[i];
    e->free_of_body[i] = -1;
    for (int a = 0; a < 3; a++) {
        e->st[i].x[a] = b->x[a];
        e->st[i].v[a] = b->v[a];
        e->st[i].w[a] = b->w[a];
    }
    for (int a = 0; a < 4; a++) e->st[i].q[a] = b->q[a];
    if (b->material < 0 || b->material >= c->nmaterial || c->materials[b->material].model == LAHAR_CONTACT_SOIL) {
        snprintf(err, errlen, "%s: body '%s': needs a DEM material (linear or hertz)", c->path, b->name);
        return -1;
    }
    if (b->motion == LAHAR_MOTION_PRESCRIBED) {
        snprintf(err, errlen,
                 "%s: body '%s': the lammps engine has no prescribed motion; make it fixed or use dem.engine: "
                 "spheropoly",
                 c->path, b->name);
        return -1;
    }
    if (b->motion == LAHAR_MOTION_FIXED) {
        if (make_wall(c, i, &e->walls[e->nwall], err, errlen) != 0) return -1;
        e->nwall++;
        return 0;
    }
    if (!lmp_is_sphere(&b->shape)) {
        snprintf(err, errlen,
                 "%s: body '%s': the lammps engine moves only spheres (3D) and discs (2D); this free body is a "
                 "sphero-polyhedron (%d vertices): use dem.engine: spheropoly",
                 c->path, b->name, b->shape.nv);
        return -1;
    }
    /* LAMMPS derives the moment of inertia from mass and radius: a body whose case gives another
     * would silently turn differently */
    double r = b->shape.radius, m = b->mass;
    double iref = (c->dim == 3 ? 0.4 : 0.5) * m * r * r, imom = c->dim == 3 ? b->inertia[0] : b->inertia[2];
    if (!(m > 0.0) || fabs(imom - iref) > 1e-9 * iref) {
        snprintf(err, errlen,
                 "%s: body '%s': mass %g kg and moment of inertia %g are not those of a solid %s (LAMMPS uses "
                 "%g); use dem.engine: spheropoly",
                 c->path, b->name, m, imom, c->dim == 3 ? "sphere" : "disc", iref);
        return -1;
    }
    int k = e->nfree++;
    e->free_of_body[i] = k;
    e->body_of_free[k] = i;
    e->mass[k] = m;
    e->radius[k] = r;
    e->inertia[k] = iref;
    return 0;
}

/* One atom type per material (Hertz) or per (material, mass) (linear: c_n depends on m*). */
static int define_atom_types(lahar_dem_engine *e, const lahar_case *c, lmp_setup *su, char *err, size_t errlen)
{
    int *tmat = su->tmat = malloc((size_t)LMP_MAX_TYPES * sizeof(int));
    double *tmass = su->tmass = malloc((size_t)LMP_MAX_TYPES * sizeof(double));
    if (!tmat || !tmass) return lmp_oom(err, errlen);
    for (int k = 0; k < e->nfree; k++) {
        int mat = c->bodies[e->body_of_free[k]].material;
        double key = c->materials[mat].model == LAHAR_CONTACT_HERTZ ? 0.0 : e->mass[k];
        int t = 0;
        while (t < e->ntype && !(tmat[t] == mat && tmass[t] == key)) t++;
        if (t == e->ntype) {
            if (e->ntype == LMP_MAX_TYPES) {
                snprintf(err, errlen,
                         "%s: more than %d distinct (material, mass) classes of free bodies with the linear law; the "
                         "lammps engine writes one LAMMPS atom type per class: use hertz materials, fewer sizes, or "
                         "dem.engine: spheropoly",
                         c->path, LMP_MAX_TYPES);
                return -1;
            }
            tmat[t] = mat;
            tmass[t] = key;
            e->ntype++;
        }
        e->type_of_free[k] = t + 1;
    }
    return 0;
}

/* Every coefficient start_lammps will write, made once here with the names of the materials and
 * walls for the message: an argument LAMMPS refuses (a Tsuji restitution it cannot express) would
 * end the process. */
static int check_coefficients(const lahar_dem_engine *e, const lahar_case *c, const lmp_setup *su, char *err,
                              size_t errlen)
{
    char coeff[512];
    for (int t = 0; t < e->ntype; t++) {
        for (int u = t; u < e->ntype; u++) {
            char what[1400];
            snprintf(what, sizeof what, "%s: materials '%s'/'%s'", c->path, c->materials[su->tmat[t]].name,
                     c->materials[su->tmat[u]].name);
            if (lmp_law_coeffs(type_law(c, su, t, u), type_mstar(su, t, u), coeff, sizeof coeff, err, errlen, what) != 0)
                return -1;
        }
        for (int w = 0; w < e->nwall; w++) {
            char what[1400];
            snprintf(what, sizeof what, "%s: body '%s'", c->path, c->bodies[e->walls[w].body].name);
            if (lmp_law_coeffs(wall_law(c, su, t, &e->walls[w]), su->tmass[t], coeff, sizeof coeff, err, errlen, what) != 0)
                return -1;
        }
    }
    return 0;
}

/* The wall fixes (one per wall and atom type) and the fixes made again before an init: every
 * wall x type (the Hertz ones are kept) and four more (external, gravity, integrator, enforce2d). */
static int alloc_fix_tables(lahar_dem_engine *e, char *err, size_t errlen)
{
    e->caprefix = e->nwall * e->ntype + 4;
    e->refix_id = calloc((size_t)e->caprefix, sizeof *e->refix_id);
    e->wfix_id = calloc((size_t)(e->nwall * e->ntype + 1), sizeof *e->wfix_id);
    e->wfix_wall = calloc((size_t)(e->nwall * e->ntype + 1), sizeof *e->wfix_wall);
    e->refix_cmd = calloc((size_t)e->caprefix, sizeof *e->refix_cmd);
    if (!e->refix_id || !e->refix_cmd || !e->wfix_id || !e->wfix_wall) return lmp_oom(err, errlen);
    return 0;
}

/* ---- create: LAMMPS ---------------------------------------------------------------------------- */

/* One serial instance that writes nothing of its own (no log, screen or citation file): the node's
 * output is lahar's. The boundaries shrink-wrap, so that no atom can be lost (README.md "Limits of
 * the build"); in 2D z is periodic. */
static int open_lammps(lahar_dem_engine *e, const lahar_case *c, char *err, size_t errlen)
{
    const char *args[] = {"lahar-dem", "-log", "none", "-screen", "none", "-nocite"};
    e->lmp = lammps_open_no_mpi((int)(sizeof args / sizeof args[0]), (char **)args, NULL);
    if (!e->lmp) {
        snprintf(err, errlen, "lammps engine: lammps_open_no_mpi failed");
        return -1;
    }
    lmp_cmd(e, "units si");
    lmp_cmd(e, "dimension %d", c->dim);
    lmp_cmd(e, "atom_style sphere");
    lmp_cmd(e, "atom_modify map array sort 0 0.0");
    lmp_cmd(e, c->dim == 3 ? "boundary m m m" : "boundary m m p");
    lmp_cmd(e, "comm_modify vel yes");
    lmp_cmd(e, "newton off");
    return 0;
}

/* The box only has to hold the free bodies at the start (it shrink-wraps from there), with one
 * largest radius to spare. Returns the smallest radius, which sets the neighbour skin. */
static double create_box(lahar_dem_engine *e, const lahar_case *c)
{
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, rmin = DBL_MAX, rmax = 0.0;
    for (int k = 0; k < e->nfree; k++) {
        const double *x = c->bodies[e->body_of_free[k]].x;
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], x[a] - e->radius[k]);
            hi[a] = fmax(hi[a], x[a] + e->radius[k]);
        }
        rmin = fmin(rmin, e->radius[k]);
        rmax = fmax(rmax, e->radius[k]);
    }
    if (e->nfree == 0) {
        for (int a = 0; a < 3; a++) lo[a] = -1.0, hi[a] = 1.0;
        rmin = rmax = 1.0;
    }
    /* 2D: z is periodic; its period (> 4 rmax) keeps the periodic images out of contact */
    if (c->dim == 2) lo[2] = -2.0 * rmax - 0.5, hi[2] = 2.0 * rmax + 0.5;
    for (int a = 0; a < c->dim; a++) lo[a] -= rmax, hi[a] += rmax;
    lmp_cmd(e, "region lahar_box block %.17g %.17g %.17g %.17g %.17g %.17g", lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
    lmp_cmd(e, "create_box %d lahar_box", e->ntype > 0 ? e->ntype : 1);
    return rmin;
}

/* The free bodies as atoms, tag = 1 + index among the free bodies; radius, mass and spin are set
 * in LAMMPS' arrays afterwards (lammps_create_atoms takes positions and velocities only). */
static int create_atoms(lahar_dem_engine *e, const lahar_case *c, char *err, size_t errlen)
{
    int *ids = malloc((size_t)e->nfree * sizeof(int));
    double *xs = malloc((size_t)e->nfree * 3 * sizeof(double)), *vs = malloc((size_t)e->nfree * 3 * sizeof(double));
    if (!ids || !xs || !vs) {
        free(ids);
        free(xs);
        free(vs);
        return lmp_oom(err, errlen);
    }
    for (int k = 0; k < e->nfree; k++) {
        const lahar_body *b = &c->bodies[e->body_of_free[k]];
        ids[k] = k + 1;
        for (int a = 0; a < 3; a++) xs[3 * k + a] = b->x[a], vs[3 * k + a] = b->v[a];
        if (c->dim == 2) xs[3 * k + 2] = vs[3 * k + 2] = 0.0;
    }
    lammps_create_atoms(e->lmp, e->nfree, ids, e->type_of_free, xs, vs, NULL, 0);
    free(ids);
    free(xs);
    free(vs);
    int nlocal = lammps_extract_setting(e->lmp, "nlocal");
    int *id = lammps_extract_atom(e->lmp, "id");
    double *rad = lammps_extract_atom(e->lmp, "radius"), *rm = lammps_extract_atom(e->lmp, "rmass");
    double **om = lammps_extract_atom(e->lmp, "omega");
    if (nlocal != e->nfree) {
        snprintf(err, errlen, "lammps engine: LAMMPS created %d of %d spheres", nlocal, e->nfree);
        return -1;
    }
    for (int i = 0; i < nlocal; i++) {
        int k = id[i] - 1;
        const lahar_body *b = &c->bodies[e->body_of_free[k]];
        rad[i] = e->radius[k];
        rm[i] = e->mass[k];
        for (int a = 0; a < 3; a++) om[i][a] = c->dim == 2 && a < 2 ? 0.0 : b->w[a];
    }
    return 0;
}

/* Neighbour lists checked at every substep, and the contact law of every pair of atom types
 * (without free bodies the box still has one type, and LAMMPS' init refuses a type without
 * coefficients). lmp_law_coeffs cannot fail here: check_coefficients made the same calls. */
static void write_pair_coeffs(lahar_dem_engine *e, const lahar_case *c, const lmp_setup *su, double rmin, char *err,
                              size_t errlen)
{
    char coeff[512];
    lmp_cmd(e, "neighbor %.17g bin", 0.25 * rmin);
    lmp_cmd(e, "neigh_modify delay 0 every 1 check yes");
    lmp_cmd(e, "pair_style granular");
    if (e->ntype == 0) lmp_cmd(e, "pair_coeff * * hooke 1 0 tangential linear_nohistory 0 0");
    for (int t = 0; t < e->ntype; t++)
        for (int u = t; u < e->ntype; u++) {
            lmp_law_coeffs(type_law(c, su, t, u), type_mstar(su, t, u), coeff, sizeof coeff, err, errlen, "");
            lmp_cmd(e, "pair_coeff %d %d %s", t + 1, u + 1, coeff);
        }
}

/* One fix wall/gran/region per wall and atom type (a wall's law depends on the free body's type),
 * each with `contacts` so that accumulate_wall_forces can report the wall's force. The linear
 * fixes come first; the Hertz ones follow and are kept, since lmp_refix must make them anew (and
 * everything after them) before every init but the first (README.md "Step"). */
static void create_walls(lahar_dem_engine *e, const lahar_case *c, const lmp_setup *su, char *err, size_t errlen)
{
    char coeff[512];
    for (int t = 0; t < e->ntype; t++) lmp_cmd(e, "group lahar_t%d type %d", t + 1, t + 1);
    for (int w = 0; w < e->nwall; w++) {
        const lmp_wall *wl = &e->walls[w];
        lmp_cmd(e, "region lahar_w%d plane %.17g %.17g %.17g %.17g %.17g %.17g side in", w, wl->p[0], wl->p[1], wl->p[2],
                wl->n[0], wl->n[1], wl->n[2]);
        for (int t = 0; t < e->ntype; t++) {
            const dem_pair_law *law = wall_law(c, su, t, wl);
            lmp_law_coeffs(law, su->tmass[t], coeff, sizeof coeff, err, errlen, "");
            if (law->model == LAHAR_CONTACT_HERTZ) continue; /* after the linear ones, below */
            snprintf(e->wfix_id[e->nwfix], sizeof e->wfix_id[0], "lahar_w%d_%d", w, t + 1);
            e->wfix_wall[e->nwfix++] = w;
            lmp_cmd(e, "fix lahar_w%d_%d lahar_t%d wall/gran/region granular %s region lahar_w%d contacts", w, t + 1,
                    t + 1, coeff, w);
        }
    }
    for (int w = 0; w < e->nwall; w++) {
        const lmp_wall *wl = &e->walls[w];
        for (int t = 0; t < e->ntype; t++) {
            const dem_pair_law *law = wall_law(c, su, t, wl);
            if (law->model != LAHAR_CONTACT_HERTZ) continue;
            lmp_law_coeffs(law, su->tmass[t], coeff, sizeof coeff, err, errlen, "");
            char id[32];
            snprintf(id, sizeof id, "lahar_w%d_%d", w, t + 1);
            snprintf(e->wfix_id[e->nwfix], sizeof e->wfix_id[0], "%s", id);
            e->wfix_wall[e->nwfix++] = w;
            lmp_keep_fix(e, id, "fix %s lahar_t%d wall/gran/region granular %s region lahar_w%d contacts", id, t + 1,
                         coeff, w);
        }
    }
}

/* The fixes of the step, after the walls (post_force runs in this order: the callback must see
 * the walls' forces and none of gravity) and kept for lmp_refix: the SPH loads and the report
 * (fix external, lmp_callback), gravity, the integrator, and in 2D enforce2d. */
static void add_step_fixes(lahar_dem_engine *e, const lahar_case *c)
{
    lmp_keep_fix(e, "lahar_ext", "fix lahar_ext all external pf/callback 1 1");
    lammps_set_fix_external_callback(e->lmp, "lahar_ext", lmp_callback, e);
    vec3 gv = v3(c->gravity[0], c->gravity[1], c->dim == 3 ? c->gravity[2] : 0.0);
    double g = v3_norm(gv);
    if (g > 0.0)
        lmp_keep_fix(e, "lahar_g", "fix lahar_g all gravity %.17g vector %.17g %.17g %.17g", g, gv.x / g, gv.y / g,
                     gv.z / g);
    lmp_keep_fix(e, "lahar_nve", c->dim == 3 ? "fix lahar_nve all nve/sphere" : "fix lahar_nve all nve/sphere disc");
    if (c->dim == 2) lmp_keep_fix(e, "lahar_2d", "fix lahar_2d all enforce2d");
}

/* LAMMPS from the checked engine: every command below has been made acceptable beforehand. */
static int start_lammps(lahar_dem_engine *e, const lahar_case *c, const lmp_setup *su, char *err, size_t errlen)
{
    if (open_lammps(e, c, err, errlen) != 0) return -1;
    double rmin = create_box(e, c);
    if (e->nfree > 0 && create_atoms(e, c, err, errlen) != 0) return -1;
    write_pair_coeffs(e, c, su, rmin, err, errlen);
    create_walls(e, c, su, err, errlen);
    add_step_fixes(e, c);
    lmp_cmd(e, "thermo_style custom step");
    lmp_cmd(e, "thermo 0");
    return 0;
}

/* Everything up to LAMMPS itself; with start = 0 the engine is returned before LAMMPS is opened,
 * so that check_case can run every refusal without starting it. */
static lahar_dem_engine *lmp_build(const lahar_case *c, int start, char *err, size_t errlen)
{
    /* everything LAMMPS could refuse is checked before LAMMPS starts (no exceptions in this build) */
    if (check_case_sections(c, err, errlen) != 0) return NULL;
    lahar_dem_engine *e = calloc(1, sizeof *e);
    if (!e) {
        lmp_oom(err, errlen);
        return NULL;
    }
    lmp_setup su = {0};
    if (alloc_engine(e, c, &su, err, errlen) != 0 || make_pair_laws(c, su.laws, err, errlen) != 0) goto fail;
    for (int i = 0; i < c->nbody; i++)
        if (take_body(e, c, i, err, errlen) != 0) goto fail;
    if (define_atom_types(e, c, &su, err, errlen) != 0 || check_coefficients(e, c, &su, err, errlen) != 0 ||
        alloc_fix_tables(e, err, errlen) != 0)
        goto fail;
    e->dt_stable = stable_dt_of(c, su.laws, err, errlen);
    if (!(e->dt_stable > 0.0)) goto fail;
    if (start && start_lammps(e, c, &su, err, errlen) != 0) goto fail;
    setup_free(&su);
    return e;
fail:
    setup_free(&su);
    lmp_destroy(e);
    return NULL;
}

lahar_dem_engine *lmp_create(const lahar_case *c, char *err, size_t errlen) { return lmp_build(c, 1, err, errlen); }

/* The case's bodies, walls, materials and sections this engine can run (lahar validate, lahar run
 * before any node starts): the refusals of create, without LAMMPS. */
int lmp_check_case(const lahar_case *c, char *err, size_t errlen)
{
    lahar_dem_engine *e = lmp_build(c, 0, err, errlen);
    if (!e) return -1;
    lmp_destroy(e);
    return 0;
}
