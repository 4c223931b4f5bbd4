/* lahar_case <-> lahar_scene_t (see scene_msg.h). */
#include "scene_msg.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "case.h"
#include "errmsg.h"
#include "msg_check.h"
#include "scene_msg_fields.h"

static void scene_copy_name(char dst[LAHAR_NAME_MAX], const char *src)
{
    snprintf(dst, LAHAR_NAME_MAX, "%s", src ? src : "");
}

/* The fields a message carries under the same name as the in-memory case, listed once and copied
 * both ways by the macros of scene_msg_fields.h. A field added to a .lcm type and to scene.h is
 * added here once. */
#define SPH_NUM_FIELDS(X) X(h_over_dx) X(c0) X(gamma) X(mu) X(alpha) X(delta) X(cfl) X(cfl_force) X(cfl_visc) \
    X(shepard_interval) X(shifting) X(background_pressure) X(sps_cs) X(halo) X(kappa) X(riemann_limiter)
#define SPH_FLAG_FIELDS(X) X(shifting_density) X(transport_velocity) X(sps)
#define SPH_CODE_FIELDS(X) X(eos) X(body_layers) X(wall_viscous) X(initial_pressure) X(wall_pressure) \
    X(penalty_stiffness) X(soil_wall_stress) X(scheme)
#define SPH_ARRAY_FIELDS(X) X(body_force) X(lo) X(hi)
#define MATERIAL_NUM_FIELDS(X) X(density) X(young) X(poisson) X(kn) X(kt_ratio) X(restitution) X(friction) \
    X(friction_angle) X(cohesion) X(dilatancy) X(permeability) X(damping) X(av_alpha) X(av_beta)
#define MATERIAL_CODE_FIELDS(X) X(model) X(constitutive)
#define BODY_NUM_FIELDS(X) X(mass)
#define BODY_ARRAY_FIELDS(X) X(inertia) X(x) X(q) X(w) /* the velocity: v in the case, vel in the message */
#define PROBE_NUM_FIELDS(X) X(top) X(body) X(size) X(rate)
#define PROBE_CODE_FIELDS(X) X(kind) X(axis)
#define PROBE_ARRAY_FIELDS(X) X(x) X(n) X(hi)


/* The kernel string points into from (keep it alive while to is used). */
static void scene_sph_to_msg(const lahar_sph_options *from, lahar_sph_options_t *to)
{
    to->kernel = (char *)from->kernel;
    SPH_NUM_FIELDS(TO_MSG_NUM)
    SPH_FLAG_FIELDS(TO_MSG_FLAG)
    SPH_CODE_FIELDS(TO_MSG_CODE)
    SPH_ARRAY_FIELDS(COPY_ARRAY)
    for (int a = 0; a < 3; a++)
        to->periodic[a] = (int8_t)(from->periodic[a] != 0);
}

static void scene_sph_from_msg(const lahar_sph_options_t *from, lahar_sph_options *to)
{
    scene_copy_name(to->kernel, from->kernel);
    SPH_NUM_FIELDS(TO_MSG_NUM)
    SPH_FLAG_FIELDS(FROM_MSG_FLAG)
    SPH_CODE_FIELDS(FROM_MSG_CODE)
    SPH_ARRAY_FIELDS(COPY_ARRAY)
    for (int a = 0; a < 3; a++)
        to->periodic[a] = from->periodic[a] != 0;
}

/* The case's scalars: time, output, engine, stability limits and the sph options. */
static void scene_settings_to_msg(const lahar_case *c, lahar_scene_t *m)
{
    m->dim = c->dim;
    memcpy(m->gravity, c->gravity, sizeof m->gravity);
    m->t_end = c->t_end;
    m->dt_max = c->dt_max;
    m->dt_min = c->dt_min;
    m->output_interval = c->output_interval;
    m->forces_interval = c->forces_interval;
    m->case_path = (char *)c->path;
    m->resume_dir = (char *)(c->resume ? c->resume_dir : "");
    m->resume_step = c->resume ? c->resume_step : -1;
    m->output_fields = (int32_t)c->output_fields;
    m->output_forces = (int8_t)(c->output_forces != 0);
    m->output_in_place = (int8_t)(c->output_in_place != 0);
    m->dem_engine = (char *)c->dem_engine;
    m->dem_dt_safety = c->dem_dt_safety;
    memcpy(m->stability_density_band, c->stability.density_band, sizeof m->stability_density_band);
    m->stability_max_overlap = c->stability.max_overlap;
    m->stability_dt_collapse = c->stability.dt_collapse;
    m->sph_dx = c->sph_dx;
    m->sph_density = c->sph_density;
    scene_sph_to_msg(&c->sph, &m->sph);
}

static void scene_probe_to_msg(const lahar_probe *from, lahar_probe_t *to)
{
    to->name = (char *)from->name;
    PROBE_NUM_FIELDS(TO_MSG_NUM)
    PROBE_CODE_FIELDS(TO_MSG_CODE)
    PROBE_ARRAY_FIELDS(COPY_ARRAY)
}

/* Body i: its shape's arrays by reference (the message's row pointers are allocated here), its
 * mass properties and state. */
static int scene_body_to_msg(const lahar_case *c, int i, lahar_scene_t *m)
{
    const lahar_body *a = &c->bodies[i];
    const lahar_shape *s = &a->shape;
    lahar_body_t *b = &m->bodies[i];
    b->id = i;
    b->name = (char *)a->name;
    b->material = a->material;
    b->motion = (int8_t)a->motion;
    b->convex = (int8_t)(a->convex != 0);
    b->radius = s->radius;
    b->nv = s->nv;
    b->v = calloc((size_t)(s->nv > 0 ? s->nv : 1), sizeof *b->v);
    b->ne = s->ne;
    b->e = calloc((size_t)(s->ne > 0 ? s->ne : 1), sizeof *b->e);
    b->nf = s->nf;
    b->face_start = calloc((size_t)(s->nf > 0 ? s->nf : 1), sizeof *b->face_start);
    b->face_nv = calloc((size_t)(s->nf > 0 ? s->nf : 1), sizeof *b->face_nv);
    if (!b->v || !b->e || !b->face_start || !b->face_nv)
        return -1;
    for (int k = 0; k < s->nv; k++)
        b->v[k] = (double *)s->v[k];
    for (int k = 0; k < s->ne; k++)
        b->e[k] = (int32_t *)s->e[k];
    for (int f = 0; f < s->nf; f++) {
        b->face_start[f] = s->face_start[f];
        b->face_nv[f] = s->face_start[f + 1] - s->face_start[f];
    }
    b->nfv = s->nf > 0 ? s->face_start[s->nf] : 0;
    b->face_v = (int32_t *)s->face_v;
    const lahar_body *from = a;
    lahar_body_t *to = b;
    BODY_NUM_FIELDS(TO_MSG_NUM)
    BODY_ARRAY_FIELDS(COPY_ARRAY)
    memcpy(to->vel, from->v, sizeof to->vel);
    m->body_record_contacts[i] = a->record_contacts != 0;
    return 0;
}

/* Particle block i: its expressions and mesh by reference (row pointers allocated here). */
static int scene_block_to_msg(const lahar_particle_block *a, lahar_particle_block_t *b)
{
    b->name = (char *)a->name;
    b->kind = (int8_t)a->kind;
    memcpy(b->lo, a->lo, sizeof b->lo);
    memcpy(b->hi, a->hi, sizeof b->hi);
    memcpy(b->v, a->v, sizeof b->v);
    b->source = (char *)a->source;
    b->phase = (int8_t)a->phase;
    b->material = a->material;
    for (int k = 0; k < 3; k++)
        b->velocity_expr[k] = (char *)a->vexpr[k];
    b->pressure_expr = (char *)a->pexpr;
    b->initial_file = (char *)a->init_file;
    b->nvert = a->nvert;
    b->ntri = a->ntri;
    b->vert = calloc((size_t)(a->nvert > 0 ? a->nvert : 1), sizeof *b->vert);
    b->tri = calloc((size_t)(a->ntri > 0 ? a->ntri : 1), sizeof *b->tri);
    if (!b->vert || !b->tri)
        return -1;
    for (int k = 0; k < a->nvert; k++)
        b->vert[k] = (double *)a->vert[k];
    for (int k = 0; k < a->ntri; k++)
        b->tri[k] = (int32_t *)a->tri[k];
    return 0;
}

int lahar_scene_msg_from_case(const lahar_case *c, const char *output_dir, int has_dem, int has_sph,
                              int64_t run_id, lahar_scene_t *m)
{
    memset(m, 0, sizeof *m);
    m->run_id = run_id;
    m->step = -1;
    m->output_dir = (char *)output_dir;
    m->has_dem = (int8_t)(has_dem != 0);
    m->has_sph = (int8_t)(has_sph != 0);
    scene_settings_to_msg(c, m);

    m->nmaterial = c->nmaterial;
    m->materials = calloc((size_t)(c->nmaterial > 0 ? c->nmaterial : 1), sizeof *m->materials);
    m->nbody = c->nbody;
    m->bodies = calloc((size_t)(c->nbody > 0 ? c->nbody : 1), sizeof *m->bodies);
    m->body_record_contacts = calloc((size_t)(c->nbody > 0 ? c->nbody : 1), sizeof *m->body_record_contacts);
    m->nblock = c->nblock;
    m->blocks = calloc((size_t)(c->nblock > 0 ? c->nblock : 1), sizeof *m->blocks);
    m->nprobe = c->nprobe;
    m->probes = calloc((size_t)(c->nprobe > 0 ? c->nprobe : 1), sizeof *m->probes);
    if (!m->materials || !m->bodies || !m->body_record_contacts || !m->blocks || !m->probes ||
        lahar_scene_msg_inflow_from_case(c, m) != 0)
        goto fail;
    for (int i = 0; i < c->nprobe; i++)
        scene_probe_to_msg(&c->probes[i], &m->probes[i]);
    for (int i = 0; i < c->nmaterial; i++) {
        const lahar_material *from = &c->materials[i];
        lahar_material_t *to = &m->materials[i];
        to->name = (char *)from->name;
        MATERIAL_NUM_FIELDS(TO_MSG_NUM)
        MATERIAL_CODE_FIELDS(TO_MSG_CODE)
    }
    for (int i = 0; i < c->nbody; i++)
        if (scene_body_to_msg(c, i, m) != 0)
            goto fail;
    for (int i = 0; i < c->nblock; i++)
        if (scene_block_to_msg(&c->blocks[i], &m->blocks[i]) != 0)
            goto fail;
    return 0;
fail:
    lahar_scene_msg_release(m);
    return -1;
}

void lahar_scene_msg_release(lahar_scene_t *m)
{
    if (m->bodies)
        for (int i = 0; i < m->nbody; i++) {
            free(m->bodies[i].v);
            free(m->bodies[i].e);
            free(m->bodies[i].face_start);
            free(m->bodies[i].face_nv);
        }
    if (m->blocks)
        for (int i = 0; i < m->nblock; i++) {
            free(m->blocks[i].vert);
            free(m->blocks[i].tri);
        }
    free(m->materials);
    free(m->bodies);
    free(m->body_record_contacts);
    free(m->blocks);
    free(m->probes);
    lahar_scene_msg_inflow_release(m);
    memset(m, 0, sizeof *m);
}

/* The decoding of the scene message (lahar_scene_msg_to_case): each part returns 0, SCENE_BAD
 * with the reason in err (a message no lahar sent; the fuzzers send such), or SCENE_OOM. */
enum { SCENE_BAD = -1, SCENE_OOM = -2 };

/* The counts, the dimension and the options that travel as small integers: each must name one of
 * its enum's values. */
static int scene_header_check(const lahar_scene_t *m, char *err, size_t errlen)
{
    if (m->nmaterial < 0 || m->nbody < 0 || m->nblock < 0 || m->nprobe < 0 || (m->dim != 2 && m->dim != 3)) {
        lahar_errf(err, errlen, "malformed scene message (counts or dimension)");
        return SCENE_BAD;
    }
    const lahar_sph_options_t *so = &m->sph;
    if (so->eos < 0 || so->eos > LAHAR_SPH_EOS_TAIT || so->wall_viscous < 0 || so->wall_viscous > LAHAR_SPH_WALL_PAPER ||
        so->initial_pressure < 0 || so->initial_pressure > LAHAR_SPH_INITIAL_PRESSURE_HYDROSTATIC ||
        so->wall_pressure < 0 || so->wall_pressure > LAHAR_SPH_WALL_PRESSURE_GHOST || so->penalty_stiffness < 0 ||
        so->penalty_stiffness > LAHAR_SPH_PENALTY_ACOUSTIC || so->soil_wall_stress < 0 ||
        so->soil_wall_stress > LAHAR_SPH_WALL_PRESSURE_GHOST || so->scheme < 0 || so->scheme > LAHAR_SPH_SCHEME_RIEMANN) {
        lahar_errf(err, errlen, "malformed scene message (sph options)");
        return SCENE_BAD;
    }
    for (int i = 0; i < m->nmaterial; i++)
        if (m->materials[i].model < LAHAR_CONTACT_LINEAR || m->materials[i].model > LAHAR_CONTACT_SOIL) {
            lahar_errf(err, errlen, "malformed scene message (material %d: contact model)", i);
            return SCENE_BAD;
        }
    return 0;
}

/* The case's scalars: paths, time, output, engine, stability limits and the sph options. */
static void scene_settings_from_msg(const lahar_scene_t *m, lahar_case *c)
{
    snprintf(c->path, sizeof c->path, "%s", m->case_path ? m->case_path : "");
    c->resume = m->resume_dir && m->resume_dir[0] && m->resume_step >= 0;
    c->resume_step = c->resume ? m->resume_step : 0;
    snprintf(c->resume_dir, sizeof c->resume_dir, "%s", c->resume ? m->resume_dir : "");
    c->dim = m->dim;
    c->output_fields = (unsigned)m->output_fields;
    c->output_forces = m->output_forces;
    c->output_in_place = m->output_in_place;
    memcpy(c->gravity, m->gravity, sizeof c->gravity);
    c->t_end = m->t_end;
    c->dt_max = m->dt_max;
    c->dt_min = m->dt_min;
    c->output_interval = m->output_interval;
    c->forces_interval = m->forces_interval;
    scene_copy_name(c->dem_engine, m->dem_engine);
    c->dem_dt_safety = m->dem_dt_safety;
    memcpy(c->stability.density_band, m->stability_density_band, sizeof c->stability.density_band);
    c->stability.max_overlap = m->stability_max_overlap;
    c->stability.dt_collapse = m->stability_dt_collapse;
    c->sph_dx = m->sph_dx;
    c->sph_density = m->sph_density;
    scene_sph_from_msg(&m->sph, &c->sph);
}

/* Body i's shape indices: the engines index vertices by edge and face entries, and faces by
 * face_start, so every index must lie in its array (face f is face_v[face_start[f] ..
 * face_start[f + 1])). */
static int scene_body_indices_ok(const lahar_body_t *a)
{
    int bad = 0;
    for (int k = 0; k < a->ne && !bad; k++)
        bad = a->e[k][0] < 0 || a->e[k][0] >= a->nv || a->e[k][1] < 0 || a->e[k][1] >= a->nv;
    for (int f = 0; f < a->nf && !bad; f++)
        bad = a->face_start[f] < (f ? a->face_start[f - 1] : 0) || a->face_start[f] > a->nfv ||
              (int64_t)a->face_nv[f] != (int64_t)(f + 1 < a->nf ? a->face_start[f + 1] : a->nfv) - a->face_start[f];
    for (int k = 0; k < a->nfv && !bad; k++)
        bad = a->face_v[k] < 0 || a->face_v[k] >= a->nv;
    return !bad && !(a->nf > 0 && a->face_start[0] != 0) && !(a->nf == 0 && a->nfv != 0);
}

static int scene_body_from_msg(const lahar_scene_t *m, int i, lahar_body *b, char *err, size_t errlen)
{
    const lahar_body_t *a = &m->bodies[i];
    lahar_shape *s = &b->shape;
    if (a->nv < 0 || a->ne < 0 || a->nf < 0 || a->nfv < 0 || a->material < 0 || a->material >= m->nmaterial ||
        a->motion < LAHAR_MOTION_FREE || a->motion > LAHAR_MOTION_PRESCRIBED) {
        lahar_errf(err, errlen, "malformed scene message (body %d)", i);
        return SCENE_BAD;
    }
    if (!scene_body_indices_ok(a)) {
        lahar_errf(err, errlen, "malformed scene message (body %d: shape indices)", i);
        return SCENE_BAD;
    }
    scene_copy_name(b->name, a->name);
    b->material = a->material;
    b->motion = (lahar_motion)a->motion;
    b->convex = a->convex;
    s->radius = a->radius;
    s->nv = a->nv;
    s->ne = a->ne;
    s->nf = a->nf;
    s->v = malloc((size_t)(a->nv > 0 ? a->nv : 1) * sizeof *s->v);
    s->e = malloc((size_t)(a->ne > 0 ? a->ne : 1) * sizeof *s->e);
    s->face_start = malloc((size_t)(a->nf + 1) * sizeof *s->face_start);
    s->face_v = malloc((size_t)(a->nfv > 0 ? a->nfv : 1) * sizeof *s->face_v);
    if (!s->v || !s->e || !s->face_start || !s->face_v)
        return SCENE_OOM;
    for (int k = 0; k < a->nv; k++)
        memcpy(s->v[k], a->v[k], sizeof s->v[k]);
    for (int k = 0; k < a->ne; k++) {
        s->e[k][0] = a->e[k][0];
        s->e[k][1] = a->e[k][1];
    }
    for (int f = 0; f < a->nf; f++)
        s->face_start[f] = a->face_start[f];
    s->face_start[a->nf] = a->nfv;
    for (int k = 0; k < a->nfv; k++)
        s->face_v[k] = a->face_v[k];
    const lahar_body_t *from = a;
    lahar_body *to = b;
    BODY_NUM_FIELDS(TO_MSG_NUM)
    BODY_ARRAY_FIELDS(COPY_ARRAY)
    memcpy(to->v, from->vel, sizeof to->v);
    b->record_contacts = m->body_record_contacts[i] != 0;
    return 0;
}

/* A text of the message copied into a fixed buffer: present and short enough. */
static int scene_text_fits(const char *text, size_t size) { return text && strlen(text) < size; }

static int scene_block_from_msg(const lahar_scene_t *m, int i, lahar_particle_block *b, char *err, size_t errlen)
{
    const lahar_particle_block_t *a = &m->blocks[i];
    if (a->nvert < 0 || a->ntri < 0 || a->kind < LAHAR_BLOCK_BOX || a->kind > LAHAR_BLOCK_MESH) {
        lahar_errf(err, errlen, "malformed scene message (particle block %d)", i);
        return SCENE_BAD;
    }
    for (int t = 0; t < a->ntri; t++)
        for (int k = 0; k < 3; k++)
            if (a->tri[t][k] < 0 || a->tri[t][k] >= a->nvert) {
                lahar_errf(err, errlen, "malformed scene message (particle block %d, triangle %d)", i, t);
                return SCENE_BAD;
            }
    scene_copy_name(b->name, a->name);
    b->kind = (lahar_block_kind)a->kind;
    memcpy(b->lo, a->lo, sizeof b->lo);
    memcpy(b->hi, a->hi, sizeof b->hi);
    memcpy(b->v, a->v, sizeof b->v);
    snprintf(b->source, sizeof b->source, "%s", a->source ? a->source : "");
    if (a->phase < 0 || a->phase > 1 || (a->phase == 1 && (a->material < 0 || a->material >= m->nmaterial))) {
        lahar_errf(err, errlen, "malformed scene message (particle block %d: phase/material)", i);
        return SCENE_BAD;
    }
    b->phase = a->phase;
    b->material = a->material;
    for (int k = 0; k < 3; k++) {
        if (!scene_text_fits(a->velocity_expr[k], LAHAR_EXPR_MAX)) {
            lahar_errf(err, errlen, "malformed scene message (particle block %d: velocity expression)", i);
            return SCENE_BAD;
        }
        snprintf(b->vexpr[k], sizeof b->vexpr[k], "%s", a->velocity_expr[k]);
    }
    if (!scene_text_fits(a->pressure_expr, LAHAR_EXPR_MAX)) {
        lahar_errf(err, errlen, "malformed scene message (particle block %d: pressure expression)", i);
        return SCENE_BAD;
    }
    snprintf(b->pexpr, sizeof b->pexpr, "%s", a->pressure_expr);
    if (!scene_text_fits(a->initial_file, sizeof b->init_file)) {
        lahar_errf(err, errlen, "malformed scene message (particle block %d: initial file)", i);
        return SCENE_BAD;
    }
    snprintf(b->init_file, sizeof b->init_file, "%s", a->initial_file);
    if (a->nvert > 0 && !(b->vert = malloc((size_t)a->nvert * sizeof *b->vert)))
        return SCENE_OOM;
    b->nvert = a->nvert;
    if (a->ntri > 0 && !(b->tri = malloc((size_t)a->ntri * sizeof *b->tri)))
        return SCENE_OOM;
    b->ntri = a->ntri;
    for (int k = 0; k < a->nvert; k++)
        memcpy(b->vert[k], a->vert[k], sizeof b->vert[k]);
    for (int k = 0; k < a->ntri; k++)
        for (int j = 0; j < 3; j++)
            b->tri[k][j] = a->tri[k][j];
    return 0;
}

static int scene_probe_from_msg(const lahar_scene_t *m, int i, lahar_probe *to, char *err, size_t errlen)
{
    const lahar_probe_t *from = &m->probes[i];
    if (from->body < -1 || from->body >= m->nbody || !(from->size >= 0.0) || !(from->rate >= 0.0) ||
        from->kind < LAHAR_PROBE_PRESSURE || from->kind > LAHAR_PROBE_CONTROL_VOLUME || from->axis < 0 ||
        from->axis >= m->dim ||
        (from->kind == LAHAR_PROBE_LEVEL && (from->body != -1 || !(from->top > from->x[m->dim - 1])))) {
        lahar_errf(err, errlen, "malformed scene message (probe %d)", i);
        return SCENE_BAD;
    }
    scene_copy_name(to->name, from->name);
    PROBE_NUM_FIELDS(TO_MSG_NUM)
    PROBE_CODE_FIELDS(FROM_MSG_CODE)
    PROBE_ARRAY_FIELDS(COPY_ARRAY)
    return 0;
}

/* The case of a scene message, every count and index checked (it may come from the network). */
static int scene_case_from_msg(const lahar_scene_t *m, lahar_case *c, char *err, size_t errlen)
{
    int rc = scene_header_check(m, err, errlen);
    if (rc)
        return rc;
    scene_settings_from_msg(m, c);
    c->materials = calloc((size_t)(m->nmaterial > 0 ? m->nmaterial : 1), sizeof *c->materials);
    c->bodies = calloc((size_t)(m->nbody > 0 ? m->nbody : 1), sizeof *c->bodies);
    c->blocks = calloc((size_t)(m->nblock > 0 ? m->nblock : 1), sizeof *c->blocks);
    if (!c->materials || !c->bodies || !c->blocks)
        return SCENE_OOM;
    c->nmaterial = m->nmaterial;
    for (int i = 0; i < m->nmaterial; i++) {
        const lahar_material_t *from = &m->materials[i];
        lahar_material *to = &c->materials[i];
        scene_copy_name(to->name, from->name);
        MATERIAL_NUM_FIELDS(TO_MSG_NUM)
        MATERIAL_CODE_FIELDS(FROM_MSG_CODE)
    }
    c->nbody = m->nbody;
    for (int i = 0; i < m->nbody && !rc; i++)
        rc = scene_body_from_msg(m, i, &c->bodies[i], err, errlen);
    for (int i = 0; i < m->nblock && !rc; i++) {
        c->nblock = i + 1;
        rc = scene_block_from_msg(m, i, &c->blocks[i], err, errlen);
    }
    if (rc)
        return rc;
    if (m->nprobe > 0) {
        if (!(c->probes = calloc((size_t)m->nprobe, sizeof *c->probes)))
            return SCENE_OOM;
        c->nprobe = m->nprobe;
    }
    for (int i = 0; i < m->nprobe && !rc; i++)
        rc = scene_probe_from_msg(m, i, &c->probes[i], err, errlen);
    if (!rc && lahar_scene_msg_inflow_to_case(m, c, err, errlen) != 0)
        rc = SCENE_BAD;
    return rc;
}

int lahar_scene_msg_to_case(const lahar_scene_t *m, lahar_case *c, char *err, size_t errlen)
{
    memset(c, 0, sizeof *c);
    int rc = scene_case_from_msg(m, c, err, errlen);
    if (rc == SCENE_OOM)
        snprintf(err, errlen, "out of memory building the scene");
    if (rc)
        lahar_case_free(c);
    return rc ? -1 : 0;
}

/* ---- node side of the start of a run ------------------------------------------------------- */
#include <unistd.h>
#include "lahar_hello_t.h"

int lahar_node_join(lahar_link *l, int role, const char *engine, const char *version, const char *const *caps,
                    int ncaps, double wait_s, lahar_node_scene *out, char *err, size_t errlen)
{
    memset(out, 0, sizeof *out);
    lahar_link_msg msg;
    int rc = lahar_link_wait(l, LAHAR_ROLE_COORDINATOR, LAHAR_FRAME_T_MSG_HELLO, -1, (int)(wait_s * 1e3), &msg);
    if (rc != LAHAR_LINK_OK) {
        snprintf(err, errlen, "no coordinator announced a run within %.0f s", wait_s);
        return rc;
    }
    char host[256] = "";
    gethostname(host, sizeof host - 1);
    lahar_hello_t hello = {
        .run_id = lahar_link_run_id(l), .step = -1, .role = role, .engine = (char *)engine,
        .version = (char *)version, .protocol_version = 1, .ncapabilities = ncaps,
        .capabilities = (char **)caps, .host = host, .pid = (int32_t)getpid(),
    };
    int src;
    LAHAR_LINK_SEND(src, l, LAHAR_FRAME_T_MSG_HELLO, lahar_hello_t, -1, &hello);
    if (src != 0 || lahar_link_heartbeat_start(l, LAHAR_HEARTBEAT_PERIOD) != 0) {
        snprintf(err, errlen, "cannot publish (transport error)");
        return LAHAR_LINK_ERROR;
    }
    lahar_link_watch(l, LAHAR_ROLE_COORDINATOR, LAHAR_NODE_COORDINATOR_SILENCE);
    rc = lahar_link_wait(l, LAHAR_ROLE_COORDINATOR, LAHAR_FRAME_T_MSG_SCENE, -1, -1, &msg);
    if (rc == LAHAR_LINK_LOST)
        snprintf(err, errlen, "the coordinator has been silent for %.0f s before sending the scene",
                 LAHAR_NODE_COORDINATOR_SILENCE);
    if (rc != LAHAR_LINK_OK)
        return rc;
    lahar_scene_t sm;
    if (LAHAR_MSG_DECODE(lahar_scene_t, msg.data, msg.size, &sm) < 0) {
        snprintf(err, errlen, "undecodable scene message");
        return LAHAR_LINK_ERROR;
    }
    int crc = lahar_scene_msg_to_case(&sm, &out->scene, err, errlen);
    if (crc == 0) {
        snprintf(out->output_dir, sizeof out->output_dir, "%s", sm.output_dir ? sm.output_dir : ".");
        out->has_dem = sm.has_dem;
        out->has_sph = sm.has_sph;
    }
    lahar_scene_t_decode_cleanup(&sm);
    return crc == 0 ? LAHAR_LINK_OK : LAHAR_LINK_ERROR;
}

int lahar_node_send_status(lahar_link *l, int role, int64_t step, lahar_status_t *st, const char *message)
{
    st->run_id = lahar_link_run_id(l);
    st->step = step;
    st->role = role;
    lahar_link_auth_stats as = {0};
    lahar_link_auth(l, &as);
    st->auth_rejected = (int64_t)as.frames_rejected;
    st->auth_replayed = (int64_t)as.frames_replayed;
    snprintf((char *)st->message, sizeof st->message, "%s", message ? message : "");
    int rc;
    LAHAR_LINK_SEND(rc, l, LAHAR_FRAME_T_MSG_STATUS, lahar_status_t, step, st);
    return rc;
}

/* ---- per-step messages into reusable buffers --------------------------------------------- */

/* grow *p to hold n elements of elem bytes (doubling); 0 or -1 */
static int msg_grow(void **p, int32_t *cap, int32_t n, size_t elem)
{
    if (n <= *cap)
        return 0;
    int32_t c = *cap > 0 ? *cap : 16;
    while (c < n)
        c = c > INT32_MAX / 2 ? n : 2 * c;
    void *q = realloc(*p, (size_t)c * elem);
    if (!q)
        return -1;
    *p = q;
    *cap = c;
    return 0;
}

/* One field (or a run of n elements) with LCM's decoder of that primitive type. */
#define MSG_DECODE(T, ptr, count)                                                                  \
    do {                                                                                           \
        int n_ = __##T##_decode_array(data, pos, size - pos, (ptr), (count));                      \
        if (n_ < 0)                                                                                \
            return -1;                                                                             \
        pos += n_;                                                                                 \
    } while (0)

int lahar_body_state_decode(const void *data, int size, lahar_body_state_buf *b)
{
    int pos = 0;
    int64_t hash;
    MSG_DECODE(int64_t, &hash, 1);
    if (hash != __lahar_body_state_t_get_hash())
        return -1;
    MSG_DECODE(int64_t, &b->run_id, 1);
    MSG_DECODE(int64_t, &b->step, 1);
    MSG_DECODE(double, &b->t, 1);
    int32_t n;
    MSG_DECODE(int32_t, &n, 1);
    if (n < 0 || n > (size - pos) / 4)
        return -1;
    int32_t cap = b->cap, c1 = cap, c2 = cap, c3 = cap, c4 = cap;
    if (msg_grow((void **)&b->id, &cap, n, sizeof *b->id) || msg_grow((void **)&b->x, &c1, n, sizeof *b->x) ||
        msg_grow((void **)&b->q, &c2, n, sizeof *b->q) || msg_grow((void **)&b->v, &c3, n, sizeof *b->v) ||
        msg_grow((void **)&b->w, &c4, n, sizeof *b->w))
        return -1;
    b->cap = cap;
    b->n = n;
    if (n > 0) {
        /* rows of a [n][k] array follow each other on the wire: n * k values in a row */
        MSG_DECODE(int32_t, b->id, n);
        MSG_DECODE(double, &b->x[0][0], 3 * n);
        MSG_DECODE(double, &b->q[0][0], 4 * n);
        MSG_DECODE(double, &b->v[0][0], 3 * n);
        MSG_DECODE(double, &b->w[0][0], 3 * n);
    }
    return 0;
}

void lahar_body_state_buf_free(lahar_body_state_buf *b)
{
    free(b->id);
    free(b->x);
    free(b->q);
    free(b->v);
    free(b->w);
    memset(b, 0, sizeof *b);
}

int lahar_loads_decode(const void *data, int size, lahar_loads_buf *b)
{
    int pos = 0;
    int64_t hash;
    MSG_DECODE(int64_t, &hash, 1);
    if (hash != __lahar_loads_t_get_hash())
        return -1;
    MSG_DECODE(int64_t, &b->run_id, 1);
    MSG_DECODE(int64_t, &b->step, 1);
    int32_t n;
    MSG_DECODE(int32_t, &n, 1);
    if (n < 0 || n > (size - pos) / 4)
        return -1;
    int32_t cap = b->cap_body, c1 = cap, c2 = cap, c3 = cap;
    if (msg_grow((void **)&b->body_id, &cap, n, sizeof *b->body_id) ||
        msg_grow((void **)&b->force, &c1, n, sizeof *b->force) || msg_grow((void **)&b->torque, &c2, n, sizeof *b->torque) ||
        msg_grow((void **)&b->npoints, &c3, n, sizeof *b->npoints))
        return -1;
    b->cap_body = cap;
    b->nbody = n;
    if (n > 0) {
        MSG_DECODE(int32_t, b->body_id, n);
        MSG_DECODE(double, &b->force[0][0], 3 * n);
        MSG_DECODE(double, &b->torque[0][0], 3 * n);
        MSG_DECODE(int32_t, b->npoints, n);
    }
    int32_t np;
    MSG_DECODE(int32_t, &np, 1);
    if (np < 0 || np > (size - pos) / 8)
        return -1;
    /* the points of body i follow those of body i - 1: the counts must add up to ntotal, or a
     * reader of body i's points (the contact output) would index past point_x */
    int64_t sum = 0;
    for (int32_t i = 0; i < n; i++) {
        if (b->npoints[i] < 0)
            return -1;
        sum += b->npoints[i];
    }
    if (sum != np)
        return -1;
    cap = b->cap_points;
    c1 = cap;
    if (msg_grow((void **)&b->point_x, &cap, np, sizeof *b->point_x) ||
        msg_grow((void **)&b->point_f, &c1, np, sizeof *b->point_f))
        return -1;
    b->cap_points = cap;
    b->ntotal = np;
    if (np > 0) {
        MSG_DECODE(double, &b->point_x[0][0], 3 * np);
        MSG_DECODE(double, &b->point_f[0][0], 3 * np);
    }
    MSG_DECODE(double, b->reach_lo, 3);
    MSG_DECODE(double, b->reach_hi, 3);
    return 0;
}

void lahar_loads_buf_free(lahar_loads_buf *b)
{
    free(b->body_id);
    free(b->npoints);
    free(b->force);
    free(b->torque);
    free(b->point_x);
    free(b->point_f);
    memset(b, 0, sizeof *b);
}
