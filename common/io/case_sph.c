/* The case loader: the sph: section (options with the key table's defaults, periodic axes, the
 * default c0, the checks that tie keys together). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <yaml.h>

#include "case_reader.h"
#include "kernel.h"

/* --- sph: the fluid, its particle blocks and the coupling ------------------------------------ */

/* The solver core does not have these yet (sph_node/fluid/sph_fluid.h): a case asking for them is
 * rejected instead of silently running without them. Flip when the solver grows them. */
#define LAHAR_SPH_HAVE_SHEPARD 1
#define LAHAR_SPH_HAVE_SPS 1
/* the coupling (sph_node/coupling/sph_coupling.h) uses eps = dx/2 and the kernel's support */
#define LAHAR_SPH_HAVE_HALO 0
#define LAHAR_SPH_HAVE_KAPPA 0

/* periodic: {x: [lo, hi], ...} */
static void read_periodic(reader *r, yaml_node_t *n, lahar_sph_options *o)
{
    static const char *const keys3[] = {"x", "y", "z", NULL};
    static const char *const keys2[] = {"x", "y", NULL};
    rmap m;
    if (rmap_open(r, n, "sph.periodic", &m) != 0)
        return;
    rmap_check_keys(&m, r->dim == 3 ? keys3 : keys2);
    for (int a = 0; a < r->dim && !r->failed; a++) {
        double iv[2];
        if (!rmap_vec(&m, keys3[a], 2, iv, 0, ""))
            continue;
        if (!(iv[1] > iv[0])) {
            rmap_fail(&m, keys3[a], "the period [lo, hi] must have hi > lo (got [%g, %g])", iv[0], iv[1]);
            return;
        }
        o->periodic[a] = 1;
        o->lo[a] = iv[0];
        o->hi[a] = iv[1];
    }
}

/* Characteristic speed for the default c0: the free-fall speed over the fluid's height under
 * gravity + body force, the fastest initial velocity of a block, or the fastest point of a
 * moving body at t = 0 (|v| + |w| times its farthest core vertex plus its sweep radius): a body
 * faster than the water's sound speed outruns its pressure waves and crosses it (README,
 * "Stability limits": a 20 m/s boulder needs c0 >= 40 m/s). */
static double sph_reference_speed(const lahar_case *c)
{
    double g = 0, vmax = 0, lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 3; k++)
        g += (c->gravity[k] + c->sph.body_force[k]) * (c->gravity[k] + c->sph.body_force[k]);
    g = sqrt(g);
    for (int i = 0; i < c->nblock; i++) {
        const lahar_particle_block *b = &c->blocks[i];
        vmax = fmax(vmax, sqrt(b->v[0] * b->v[0] + b->v[1] * b->v[1] + b->v[2] * b->v[2]));
        /* height: extent along the vertical axis (y in 2D, z in 3D) */
        lo = fmin(lo, b->lo[c->dim - 1]);
        hi = fmax(hi, b->hi[c->dim - 1]);
    }
    for (int i = 0; i < c->nbody; i++) {
        const lahar_body *bd = &c->bodies[i];
        if (bd->motion == LAHAR_MOTION_FIXED)
            continue;
        double reach = 0.0;
        for (int k = 0; k < bd->shape.nv; k++)
            reach = fmax(reach, sqrt(bd->shape.v[k][0] * bd->shape.v[k][0] + bd->shape.v[k][1] * bd->shape.v[k][1] +
                                     bd->shape.v[k][2] * bd->shape.v[k][2]));
        reach += bd->shape.radius;
        double v = sqrt(bd->v[0] * bd->v[0] + bd->v[1] * bd->v[1] + bd->v[2] * bd->v[2]),
               w = sqrt(bd->w[0] * bd->w[0] + bd->w[1] * bd->w[1] + bd->w[2] * bd->w[2]);
        vmax = fmax(vmax, v + w * reach);
    }
    double H = hi > lo ? hi - lo : 0.0;
    return fmax(sqrt(2.0 * g * H), vmax);
}

/* The option keys of sph: (everything but dx, density, periodic and blocks) with the key table's
 * defaults; checks that tie keys together are read_sph's. dx = 0: no spacing known (the halo's
 * default dx/2 stays 0). */
static void read_sph_options(rmap *m, lahar_sph_options *o, int dim, double dx)
{
    /* choices, their order (the C enums of scene.h) and defaults: the key table */
    int kind = rd_key_choice(m, "kernel");
    snprintf(o->kernel, sizeof o->kernel, "%s", lahar_key_find(m->sec, "kernel")->choices[kind]);
    const kernel_def *kd = kernel_find(o->kernel);
    o->h_over_dx = rd_key_num(m, "h_over_dx");
    o->eos = (lahar_sph_eos)rd_key_choice(m, "eos");
    o->gamma = rd_key_num(m, "gamma");
    o->mu = rd_key_num(m, "viscosity");
    o->alpha = rd_key_num(m, "alpha");
    o->delta = rd_key_num(m, "delta");
    o->cfl = rd_key_num(m, "cfl");
    o->cfl_force = rd_key_num(m, "cfl_force");
    o->cfl_visc = rd_key_num(m, "cfl_visc");
    rmap_vec(m, "body_force", dim, o->body_force, 0, "");
    o->shepard_interval = (int)rd_key_num(m, "shepard_interval");
    o->shifting = rd_key_num(m, "shifting");
    o->sps = rd_key_bool(m, "sps");
    o->shifting_density = rd_key_bool(m, "shifting_density");
    o->transport_velocity = rd_key_bool(m, "transport_velocity");
    o->body_layers = (int)rd_key_num(m, "body_layers");
    o->sps_cs = rd_key_num(m, "sps_cs");
    o->halo = rmap_num(m, "halo", 0, 0.5 * dx, "0.005");
    o->kappa = rmap_num(m, "kappa", 0, kd ? kd->kappa : 2.0, "2");
    o->wall_viscous = (lahar_sph_wall_viscous)rd_key_choice(m, "wall_viscous");
    o->initial_pressure = (lahar_sph_initial_pressure)rd_key_choice(m, "initial_pressure");
    o->wall_pressure = (lahar_sph_wall_pressure)rd_key_choice(m, "wall_pressure");
    o->penalty_stiffness = (lahar_sph_penalty_stiffness)rd_key_choice(m, "penalty_stiffness");
    o->soil_wall_stress = (lahar_sph_wall_pressure)rd_key_choice(m, "soil_wall_stress");
    o->scheme = (lahar_sph_scheme)rd_key_choice(m, "scheme");
    o->riemann_limiter = rd_key_num(m, "riemann_limiter");
    if (o->scheme == LAHAR_SPH_SCHEME_RIEMANN) { /* its own dissipation replaces delta-SPH and Monaghan's */
        if (!rmap_get(m, "delta"))
            o->delta = 0.0;
        if (!rmap_get(m, "alpha"))
            o->alpha = 0.0;
    }
}

/* lahar_sph_options_default (case.h): read_sph_options on an empty mapping. */
void lahar_sph_options_default(lahar_sph_options *o)
{
    memset(o, 0, sizeof *o);
    yaml_document_t doc;
    char err[256];
    reader r;
    memset(&r, 0, sizeof r);
    r.path = "(defaults)";
    r.err = err;
    r.errlen = sizeof err;
    r.dim = 3;
    if (!yaml_document_initialize(&doc, NULL, NULL, NULL, 1, 1))
        return;
    int id = yaml_document_add_mapping(&doc, NULL, YAML_ANY_MAPPING_STYLE);
    r.doc = &doc;
    rmap m;
    if (id && rmap_open(&r, rd_node(&r, id), "sph", &m) == 0) {
        rmap_section(&m, "sph");
        read_sph_options(&m, o, 3, 0.0);
    }
    yaml_document_delete(&doc);
}

/* Options that only make sense with others, or that the solver does not have: the first conflict
 * is the error. */
static void check_option_pairs(rmap *m, const lahar_case *c, const kernel_def *kd, double h, double dx)
{
    const lahar_sph_options *o = &c->sph;
    if (!kd)
        rmap_fail(m, "kernel", "the kernel table (common/kernels/kernel.h) has no '%s'", o->kernel);
    else if (rmap_get(m, "gamma") && o->eos != LAHAR_SPH_EOS_TAIT)
        rmap_fail(m, "gamma", "is the exponent of eos: tait, but the case uses eos: linear; remove gamma or set "
                  "eos: tait");
    else if (o->scheme == LAHAR_SPH_SCHEME_RIEMANN && o->delta != 0.0)
        rmap_fail(m, "delta", "scheme: riemann carries its own density diffusion (Zhang et al. 2017); remove delta or "
                  "set it to 0, or use scheme: delta");
    else if (o->scheme == LAHAR_SPH_SCHEME_RIEMANN && o->alpha != 0.0)
        rmap_fail(m, "alpha", "scheme: riemann carries its own dissipation (Zhang et al. 2017); remove alpha or set it "
                  "to 0, or use scheme: delta");
    else if (rmap_get(m, "riemann_limiter") && o->scheme != LAHAR_SPH_SCHEME_RIEMANN)
        rmap_fail(m, "riemann_limiter", "is the limiter of scheme: riemann, but the case uses scheme: delta; remove it "
                  "or set scheme: riemann");
    else if (o->shepard_interval > 0 && !LAHAR_SPH_HAVE_SHEPARD)
        rmap_fail(m, "shepard_interval", "the Shepard filter is not implemented yet; remove the key or set 0");
    else if (o->sps && !LAHAR_SPH_HAVE_SPS)
        rmap_fail(m, "sps", "SPS turbulence is not implemented yet; remove the key or set false");
    else if (o->body_layers > 0 && case_first_round_body(c) < 0)
        rmap_fail(m, "body_layers", "places particles on layers around sphere (3D) or disc (2D) bodies, but the case "
                  "has none; remove the key");
    else if (o->shifting_density && !(o->shifting > 0.0))
        rmap_fail(m, "shifting_density", "corrects the density for the particle shift, but shifting is off; remove it or "
                  "set shifting > 0");
    else if (rmap_get(m, "sps_cs") && !o->sps)
        rmap_fail(m, "sps_cs", "is the Smagorinsky constant of sps: true, but sps is off; remove it or set sps: true");
    else if (!(o->kappa > 0 && o->kappa <= 4))
        rmap_fail(m, "kappa", "must be in (0, 4] (got %g); the coupling acts within kappa h of a body, the kernel's "
                  "support radius (%g for %s) by default", o->kappa, kd->kappa, o->kernel);
    else if (!(o->halo > 0 && o->halo < o->kappa * h))
        rmap_fail(m, "halo", "must be in (0, kappa h = %g) m (got %g); dx/2 = %g is usual", o->kappa * h, o->halo,
                  0.5 * dx);
    else if (!LAHAR_SPH_HAVE_HALO && fabs(o->halo - 0.5 * dx) > 1e-12 * dx)
        rmap_fail(m, "halo", "a halo other than dx/2 = %g m is not implemented yet (got %g); remove the key",
                  0.5 * dx, o->halo);
    else if (!LAHAR_SPH_HAVE_KAPPA && fabs(o->kappa - kd->kappa) > 1e-12)
        rmap_fail(m, "kappa", "a coupling range other than the kernel's support (%g h for %s) is not implemented "
                  "yet (got %g); remove the key", kd->kappa, o->kernel, o->kappa);
}

/* Particle shifting moves particles from crowded to sparse places: at a free surface that is
 * outwards. Lahar detects no free surface, so shifting is for flows driven along periodic axes
 * only (no gravity or body force along a closed axis, where water would settle). */
static void check_shifting_axes(rmap *m, const lahar_case *c, int dim)
{
    const lahar_sph_options *o = &c->sph;
    for (int a = 0; a < dim && o->shifting > 0.0; a++)
        if (!o->periodic[a] && c->gravity[a] + o->body_force[a] != 0.0) {
            rmap_fail(m, "shifting", "needs a flow without a free surface, but gravity + body_force acts along the "
                      "non-periodic axis %c (water there settles under a free surface, which shifting would push "
                      "outwards); remove shifting or drive the flow along periodic axes only", "xyz"[a]);
            return;
        }
}

/* Each period holds a whole number of particle spacings and 3 cells of the kernel support (the
 * cell lists need them, sph_particles.h). */
static void check_periods(reader *r, yaml_node_t *pn, const lahar_sph_options *o, int dim, const kernel_def *kd,
                          double h, double dx)
{
    for (int a = 0; a < dim && !r->failed; a++) {
        if (!o->periodic[a])
            continue;
        double L = o->hi[a] - o->lo[a], cells = L / dx;
        char ax[2] = {"xyz"[a], 0};
        char pk[KEY_MAX];
        snprintf(pk, sizeof pk, "sph.periodic.%s", ax);
        if (L < 3.0 * kd->kappa * h)
            rd_fail(r, pn, pk, "the period %g m is shorter than 3 kernel supports (3 x %g m); enlarge it or lower dx",
                    L, kd->kappa * h);
        else if (fabs(cells - floor(cells + 0.5)) > 1e-6 * cells)
            rd_fail(r, pn, pk, "the period %g m is not a whole number of particle spacings (%.6g dx): particles "
                    "would bunch or gap at the seam; make it a multiple of dx = %g", L, cells, dx);
    }
}

/* sph.blocks: the particle blocks, read into c->blocks; returns their list node (NULL on error). */
static yaml_node_t *read_blocks(reader *r, rmap *m, lahar_case *c)
{
    yaml_node_t *bl = rmap_get(m, "blocks");
    if (!bl) {
        rmap_missing(m, "blocks", "[{name: water, box: {lo: [0, 0, 0], hi: [0.1, 0.1, 0.1]}}]");
        return NULL;
    }
    if (bl->type != YAML_SEQUENCE_NODE || rd_seq_len(bl) == 0) {
        rd_fail(r, bl, "sph.blocks", "expected a non-empty list of particle blocks");
        return NULL;
    }
    int nb = rd_seq_len(bl);
    c->blocks = calloc((size_t)nb, sizeof *c->blocks);
    if (!c->blocks) {
        rd_fail(r, bl, "sph.blocks", "out of memory");
        return NULL;
    }
    for (int i = 0; i < nb && !r->failed; i++) {
        c->nblock = i + 1;
        case_read_block(r, rd_seq_item(r, bl, i), i, c);
    }
    return r->failed ? NULL : bl;
}

/* c0 (default 10 x the reference speed of the blocks, sph_reference_speed) and the background
 * pressure p_b (sph_node/fluid/sph_fluid.h): default 0, or rho0 c0^2 with the transport velocity
 * (Adami et al. 2013 take p_b = p0 = rho0 c0^2). */
static void read_sound_speed(rmap *m, lahar_case *c)
{
    lahar_sph_options *o = &c->sph;
    double uref = sph_reference_speed(c);
    o->c0 = rmap_num(m, "c0", 0, 10.0 * uref, "20");
    if (m->r->failed)
        return;
    if (!rmap_get(m, "c0") && !(uref > 0)) {
        rmap_fail(m, "c0", "missing required key: the fluid starts at rest with no gravity or body force, so "
                  "there is no default speed of sound; add e.g. `c0: 1.0` (about 10 x the largest expected speed)");
        return;
    }
    if (!(o->c0 > 0)) {
        rmap_fail(m, "c0", "must be > 0 m/s (got %g); about 10 x the largest expected flow speed", o->c0);
        return;
    }
    o->background_pressure = rmap_num(m, "background_pressure", 0,
                                      o->transport_velocity ? c->sph_density * o->c0 * o->c0 : 0.0, "1e4");
    if (m->r->failed)
        return;
    if (!(o->background_pressure >= 0.0))
        rmap_fail(m, "background_pressure", "must be >= 0 Pa (got %g); 0 = off, rho0 c0^2 = %g is usual with "
                  "transport_velocity", o->background_pressure, c->sph_density * o->c0 * o->c0);
}

/* The transport velocity moves particles towards sparse places, as shifting does: no free surface,
 * no walls (a body's side has no particles, the background pressure would push the water into it:
 * Adami et al. 2013 put wall particles there), water only. */
static void check_transport_velocity(rmap *m, const lahar_case *c, int dim)
{
    const lahar_sph_options *o = &c->sph;
    if (!o->transport_velocity)
        return;
    const char *why = NULL;
    char buf[256];
    for (int a = 0; a < dim && !why; a++)
        if (!o->periodic[a] && c->gravity[a] + o->body_force[a] != 0.0) {
            snprintf(buf, sizeof buf, "gravity + body_force acts along the non-periodic axis %c (a free surface "
                     "would form, which the background pressure would tear open)", "xyz"[a]);
            why = buf;
        }
    for (int a = 0; a < dim && !why; a++)
        if (!o->periodic[a]) {
            snprintf(buf, sizeof buf, "axis %c is not periodic (water would meet a free surface or a wall there; "
                     "only fully periodic domains are supported)", "xyz"[a]);
            why = buf;
        }
    if (!why && c->nbody > 0)
        why = "the case has bodies (their surfaces have no wall particles for the background pressure)";
    for (int b = 0; b < c->nblock && !why; b++)
        if (c->blocks[b].phase == 1)
            why = "the case has soil (water only)";
    if (!why && o->shifting > 0.0)
        why = "shifting is on too (the transport velocity already regularises the particles; use one of them)";
    if (!why && !(o->background_pressure > 0.0))
        why = "background_pressure is 0 (it drives the transport velocity; omit it for rho0 c0^2)";
    if (why)
        rmap_fail(m, "transport_velocity", "needs a fully periodic water-only flow, but %s", why);
}

/* The smallest step this fluid will ask for must stay above time.dt_min. */
static void check_step_above_dt_min(rmap *m, const lahar_case *c, double h)
{
    const lahar_sph_options *o = &c->sph;
    double dt_c = o->cfl * h / o->c0, nu = o->mu / c->sph_density;
    double dt_v = nu > 0 ? o->cfl_visc * h * h / nu : INFINITY;
    if (fmin(dt_c, dt_v) >= c->dt_min)
        return;
    if (dt_c <= dt_v)
        rmap_fail(m, "c0", "the acoustic step cfl h / c0 = %g s is below time.dt_min = %g s; lower c0 or dt_min",
                  dt_c, c->dt_min);
    else
        rmap_fail(m, "viscosity", "the viscous step cfl_visc h^2 / nu = %g s is below time.dt_min = %g s; "
                  "lower the viscosity or dt_min, or raise dx", dt_v, c->dt_min);
}

/* Water and soil particles share space where they seep (Trujillo-Vela et al. 2020, section 2.3): a
 * shift of the water by its own particles only would push it into the soil. */
static void check_shifting_soil(rmap *m, const lahar_case *c)
{
    for (int b = 0; b < c->nblock && c->sph.shifting > 0.0; b++)
        if (c->blocks[b].phase == 1) {
            rmap_fail(m, "shifting", "is for water-only scenes, but block '%s' is soil (water shifted by its "
                      "own particles would be pushed into the soil); remove shifting", c->blocks[b].name);
            return;
        }
}

/* Initial files: every dataset present holds one value per particle of its block. */
static void check_initial_files(reader *r, yaml_node_t *bl, lahar_case *c)
{
    for (int b = 0; b < c->nblock && !r->failed; b++) {
        const lahar_particle_block *pb = &c->blocks[b];
        if (!pb->init_file[0])
            continue;
        char key[KEY_MAX], msg[1400];
        snprintf(key, sizeof key, "sph.blocks[%d].initial.file", b & 0xffff);
        yaml_node_t *bn = rd_seq_item(r, bl, b);
        const int64_t np = lahar_case_block_lattice(c, b, NULL, 0);
        double *none[4] = {NULL, NULL, NULL, NULL};
        int found[4] = {0, 0, 0, 0};
        if (np < 0)
            rd_fail(r, bn, key, "out of memory");
        else if (case_init_file_read(pb->init_file, np, none, found, msg, sizeof msg) != 0)
            rd_fail(r, bn, key, "%s", msg);
        else if (!found[0] && !found[1] && !found[2] && !found[3])
            rd_fail(r, bn, key, "%s holds none of the datasets vx, vy, vz, pressure", pb->init_file);
        else if (found[3] && pb->phase != 0)
            rd_fail(r, bn, key, "%s: dataset 'pressure' is for water; block '%s' is soil", pb->init_file, pb->name);
        else if (found[2] && c->dim == 2)
            rd_fail(r, bn, key, "%s: dataset 'vz' in a 2D case; remove it", pb->init_file);
    }
}

void case_read_sph(reader *r, yaml_node_t *n, lahar_case *c)
{
    lahar_sph_options *o = &c->sph;
    c->sph_density = 1000.0;
    if (!n)
        return;
    const int dim = r->dim;
    rmap m;
    if (rmap_open(r, n, "sph", &m) != 0)
        return;
    rmap_section(&m, "sph");
    c->sph_dx = rd_key_num(&m, "dx");
    c->sph_density = rd_key_num(&m, "density");
    r->dx = c->sph_dx;
    if (r->failed)
        return;
    const double dx = c->sph_dx;
    read_sph_options(&m, o, dim, dx);
    const kernel_def *kd = kernel_find(o->kernel);
    yaml_node_t *pn = rmap_get(&m, "periodic");
    if (pn)
        read_periodic(r, pn, o);
    if (r->failed)
        return;
    const double h = o->h_over_dx * dx;
    /* each step below reports the first error it finds; the ones after it then do nothing */
    check_option_pairs(&m, c, kd, h, dx);
    if (!r->failed)
        check_shifting_axes(&m, c, dim);
    if (!r->failed && o->body_layers > 0)
        case_check_body_layers(&m, c);
    if (!r->failed)
        check_periods(r, pn, o, dim, kd, h, dx);
    yaml_node_t *bl = r->failed ? NULL : read_blocks(r, &m, c);
    if (!bl)
        return;
    read_sound_speed(&m, c);
    if (!r->failed)
        check_transport_velocity(&m, c, dim);
    if (!r->failed)
        check_step_above_dt_min(&m, c, h);
    if (!r->failed)
        check_shifting_soil(&m, c);
    if (r->failed)
        return;
    case_check_blocks_placement(r, bl, c);
    check_initial_files(r, bl, c);
}
