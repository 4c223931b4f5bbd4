/* SPH node loop (see sph_node.h and the lockstep in lcm_types/README.md). Per step k:
 *
 *   wait STEP(k)
 *   k = 0: evaluate the rates at t_0 (particle-particle sums and the coupling with the bodies at
 *          their initial states, K_n for dt_0): the forces on the bodies at t_0
 *   [DEM node] send LOADS(k): per body near particles the resultant force and torque at t_k
 *          (from the evaluation that ended step k-1, which used BODY_STATE(k-1), the bodies at t_k)
 *          and, for moving bodies and bodies marked record_contacts, the contact points
 *   sph_fluid_step_begin(dt_k): kick, drift, sort, EOS, SPS, particle-particle sums at t_{k+1}
 *          (no body state needed: this overlaps the DEM node's advance and the BODY_STATE latency)
 *   [DEM node, moving bodies] wait BODY_STATE(k): the bodies at t_{k+1}, after the DEM node's
 *          advance with LOADS(k)
 *   sph_fluid_step_end(dt_k, bodies at t_{k+1}): coupling forces at t_{k+1} (sent as LOADS(k+1)),
 *          vmax/amax, kick
 *   snapshot if write_output (or if a particle crossed a body surface), STATUS(k) with the
 *   solver's dt proposal for step k+1.
 *
 * So the forces the DEM node applies over step k are those of the bodies and particles at t_k,
 * and the fluid integrated over step k sees the bodies at t_k and t_{k+1} (KDK, both ends): a
 * staggered explicit coupling. The split step is bitwise the one-call sph_fluid_step
 * (tests/test_sph_split.c), so the overlap changes timing only, never results. */
#include "sph_node.h"
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "case.h"
#include "case_keys.h"
#include "checkpoint.h"
#include "errmsg.h"
#include "instability.h"
#include "lahar_body_state_t.h"
#include "lahar_loads_t.h"
#include "lahar_step_t.h"
#include "link.h"
#include "output.h"
#include "scene_msg.h"
#include "shape_build.h"
#include "transport.h"
#include "sph_inflow.h"
#include "sph_soil_model.h"
#include "sph_eos.h"
#include "sph_probes.h"
#include "vec.h"

#define ROLE LAHAR_ROLE_SPH

/* Density of pressure p by the inverse of the case's EOS (sph_node/fluid/sph_eos.h). */
static double sph_node_eos_density(const lahar_case *c, double p)
{
    return sph_eos_get(c->sph.eos)->density(p, c->sph_density, c->sph.c0, c->sph.gamma);
}

/* Initial densities of the n particles pts of one block into rho. none: rest density. hydrostatic:
 * the density whose EOS pressure is p = rho0 |g| (h_free - s), s = -x.g/|g| the height along
 * gravity (the case's gravity only, not sph.body_force, which drives flows like Poiseuille's) and
 * h_free the block's free surface, half a spacing above its highest particle centre (the top face
 * of that particle's lattice cell: exact for a box with gravity along an axis). Assumes a block is
 * one connected water body whose free surface is its top; two blocks stacked along gravity each
 * get their own surface. Without gravity the densities stay at rest. */
static void sph_node_block_density(const lahar_case *c, const double (*pts)[3], int64_t n, double *rho)
{
    const vec3 g = v3_load(c->gravity);
    const double gmag = v3_norm(g);
    if (c->sph.initial_pressure != LAHAR_SPH_INITIAL_PRESSURE_HYDROSTATIC || !(gmag > 0.0)) {
        for (int64_t i = 0; i < n; i++)
            rho[i] = c->sph_density;
        return;
    }
    const vec3 up = v3_scale(g, -1.0 / gmag);
    double top = -HUGE_VAL;
    for (int64_t i = 0; i < n; i++) {
        const double s = v3_dot(v3_load(pts[i]), up);
        top = s > top ? s : top;
    }
    const double h_free = top + 0.5 * c->sph_dx;
    for (int64_t i = 0; i < n; i++)
        rho[i] = sph_node_eos_density(c, c->sph_density * gmag * (h_free - v3_dot(v3_load(pts[i]), up)));
}

/* Append the particles of every block at the density of sph.initial_pressure
 * (sph_node_block_density) with volume dx^D, mass rho dx^D (rho0 dx^D at rest density): a
 * particle's volume m / rho is its lattice cell, so a hydrostatic start is in equilibrium on the
 * lattice (with mass rho0 dx^D the volumes of the compressed lower rows would fall short of the
 * cells they fill, and the pressure gradient that holds them rises by up to rho g h / (rho0 c0^2)):
 * the lattice points of
 * lahar_case_block_lattice, i.e. inside the block and outside every body (a particle that starts
 * inside a body would be a crossing at step 0). 0, or -1 when out of memory or p has no room. */
static int sph_node_add_blocks(sph_particles *p, const lahar_case *c)
{
    int64_t most = 0;
    for (int b = 0; b < c->nblock; b++) {
        int64_t n = lahar_case_block_lattice(c, b, NULL, 0);
        most = n > most ? n : most;
    }
    double(*pts)[3] = malloc((size_t)(most > 0 ? most : 1) * sizeof *pts);
    double *rho = malloc((size_t)(most > 0 ? most : 1) * sizeof *rho);
    double(*vel)[3] = malloc((size_t)(most > 0 ? most : 1) * sizeof *vel);
    if (!pts || !rho || !vel) {
        free(pts);
        free(rho);
        free(vel);
        return -1;
    }
    const double vol = pow(c->sph_dx, c->dim);
    int rc = 0;
    for (int b = 0; b < c->nblock && !rc; b++) {
        int64_t n = lahar_case_block_lattice(c, b, pts, most);
        rc = n < 0 ? -1 : 0;
        /* soil blocks (sph_soil.h): at the rest density of their material, stress-free */
        const int soil = c->blocks[b].phase == SPH_SOIL_PHASE;
        const double rho_b = soil ? c->materials[c->blocks[b].material].density : c->sph_density;
        const double m = rho_b * vol;
        if (n > 0 && !soil)
            sph_node_block_density(c, (const double(*)[3])pts, n, rho);
        /* per-particle initial velocity and pressure (case keys velocity: / pressure: as
         * expressions): the pressure replaces the block's density by its inverse EOS */
        const lahar_particle_block *pb = &c->blocks[b];
        if (n > 0 && !rc) {
            char err[600];
            int has_p = 0;
            if (lahar_case_block_initial(pb, (const double(*)[3])pts, n, vel, rho, &has_p, err, sizeof err) != 0) {
                fprintf(stderr, "lahar-sph: %s\n", err);
                rc = -1;
            } else if (has_p)
                for (int64_t i = 0; i < n; i++)
                    rho[i] = sph_node_eos_density(c, rho[i]);
        }
        for (int64_t i = 0; i < n && !rc; i++)
            rc = sph_particles_add(p, pts[i], vel[i], soil ? m : rho[i] * vol, soil ? rho_b : rho[i],
                                   soil ? SPH_SOIL_PHASE : 0) < 0
                     ? -1
                     : 0;
    }
    free(pts);
    free(rho);
    free(vel);
    return rc;
}

static int64_t sph_node_count(const lahar_case *c)
{
    int64_t total = 0;
    for (int b = 0; b < c->nblock; b++) {
        int64_t n = lahar_case_block_lattice(c, b, NULL, 0);
        if (n < 0)
            return -1;
        total += n;
    }
    return total;
}

int64_t lahar_sph_node_fill(sph_particles *p, const lahar_case *c)
{
    int64_t total = sph_node_count(c);
    if (total < 0 || sph_particles_init(p, total > 0 ? total : 1) != 0)
        return -1;
    if (sph_node_add_blocks(p, c) != 0) {
        sph_particles_free(p);
        return -1;
    }
    return p->n;
}

int lahar_sph_node_params(const lahar_case *c, sph_params *prm, char *err, size_t errlen)
{
    const lahar_sph_options *o = &c->sph;
    memset(prm, 0, sizeof *prm);
    prm->opt = *o; /* every default already filled by the loader */
    prm->dim = c->dim;
    prm->dx = c->sph_dx;
    prm->rho0 = c->sph_density;
    for (int a = 0; a < 3; a++)
        prm->body_force[a] = c->gravity[a] + o->body_force[a];
    for (int b = 0; b < c->nblock; b++) /* one soil material per case (the loader checks) */
        if (c->blocks[b].phase == SPH_SOIL_PHASE && c->blocks[b].material >= 0 && c->blocks[b].material < c->nmaterial) {
            const lahar_material *mt = &c->materials[c->blocks[b].material];
            /* the constitutive model by its name in the key table (the case's choice) */
            const lahar_key *ck = lahar_key_find(lahar_key_section_find("materials.NAME"), "constitutive");
            int nchoice = 0;
            while (ck && ck->choices[nchoice])
                nchoice++;
            const sph_soil_model *model = mt->constitutive >= 0 && mt->constitutive < nchoice
                                              ? sph_soil_model_find(ck->choices[mt->constitutive])
                                              : NULL;
            if (!model) {
                snprintf(err, errlen, "materials.%s.constitutive: model %d is not one this SPH node has (%s); "
                         "update lahar-sph", mt->name, mt->constitutive,
                         mt->constitutive >= 0 && mt->constitutive < nchoice ? ck->choices[mt->constitutive] : "?");
                return -1;
            }
            prm->soil = 1;
            prm->soil_mat = (sph_soil_material){.density = mt->density, .young = mt->young, .poisson = mt->poisson,
                                                .phi = mt->friction_angle, .cohesion = mt->cohesion,
                                                .psi = mt->dilatancy, .kh = mt->permeability, .mu_phi = mt->friction,
                                                .damping = mt->damping, .av_alpha = mt->av_alpha,
                                                .av_beta = mt->av_beta, .rho_water = c->sph_density,
                                                .gravity = {c->gravity[0], c->gravity[1], c->gravity[2]},
                                                .g_ref = v3_norm(v3_load(c->gravity)) > 0.0
                                                             ? v3_norm(v3_load(c->gravity))
                                                             : 9.81,
                                                .model = model};
        }
    /* options of the case the solver core does not offer yet: refuse rather than ignore */
    if (o->halo > 0.0 && fabs(o->halo - 0.5 * c->sph_dx) > 1e-12 * c->sph_dx) {
        snprintf(err, errlen, "sph.halo: the coupling uses eps = dx/2 = %g m; another halo (%g m) is not implemented yet",
                 0.5 * c->sph_dx, o->halo);
        return -1;
    }
    const kernel_def *kd = kernel_find(o->kernel);
    if (o->kappa > 0.0 && kd && fabs(o->kappa - kd->kappa) > 1e-12) {
        snprintf(err, errlen, "sph.kappa: the coupling range is the kernel's support (%g h); %g h is not implemented yet",
                 kd->kappa, o->kappa);
        return -1;
    }
    return 0;
}

/* ---- the node -------------------------------------------------------------------------------- */

typedef struct {
    lahar_link *link;
    lahar_node_scene ns;
    sph_fluid f;
    int fluid_ready;
    lahar_particle_output *out;
    int nbody, nmoving;
    lahar_body_state *states;    /* per body: the poses the coupling uses (fixed: the scene's) */
    lahar_body_state_buf bodies; /* BODY_STATE decoded in place */
    /* LOADS being built (rows point into preallocated arrays / the coupling's contact list) */
    int32_t *l_id, *l_np;
    double (*l_force)[3], (*l_torque)[3];
    double **l_pforce, **l_ptorque;
    double **l_px, **l_pf;
    int64_t l_pcap;
    int64_t last_snapshot;       /* step of the last snapshot written */
    /* work counters the solver does not keep itself (sph_fluid.work_* are its own) */
    int64_t work_particle_body;  /* coupling contacts summed over the coupling's evaluations */
    int64_t work_output_derived; /* values computed only to be written (snapshot pressures) */
    double *out_pressure;        /* per particle: snapshot pressure; allocated only when written */
    /* A scene whose bodies are all fixed runs without a DEM node (nothing for it to integrate):
     * this node then writes what the DEM node would have, from the same numbers (sph_node_fixed_*). */
    int fixed_only;
    lahar_body_output *bout;     /* bodies.h5, forces.h5 */
    lahar_contact_output *cout;  /* contacts.h5 (NULL unless a body is marked record_contacts) */
    lahar_body_report *reports;
    double (*c_x)[3], (*c_f)[3]; /* contact points and forces, contiguous, for contacts.h5 */
    int64_t c_cap;
    int at_output_time;          /* step k starts at an output time (contacts.h5 is written then) */
    double kinetic_energy;       /* of the last snapshot (J, J/m in 2D) */
    /* pressure probes (probes: in the case; nothing allocated or sampled without them) */
    sph_probes probes;
    lahar_gauge_output *gauges;
    /* open boundaries (inlets:, outlets:, domain:; nothing set up or run without them) */
    int has_flow;
    sph_inflow flow;
} sph_node;

static int sph_node_fixed_snapshot(sph_node *s, int64_t step, double t);

/* A particle snapshot of the fields the case writes (output.fields), nothing else: unselected
 * fields are neither gathered nor computed. The pressure written is the EOS of the density
 * written (Trujillo-Vela et al. 2020, eq. 3 / Canelas et al. 2015, eq. 19), computed here only when the case writes pressure: the
 * solver's own pressure array belongs to its last evaluation (the predicted density at the end
 * of the step, before the second kick and any Shepard filter), so a snapshot's density and
 * pressure agree exactly, whatever the solver stores. */
static int sph_node_snapshot(sph_node *s, int64_t step, double t)
{
    const sph_particles *p = &s->f.p;
    const unsigned fields = s->ns.scene.output_fields;
    const int vel = (fields & LAHAR_PFIELD_VELOCITY) != 0;
    lahar_particles_view v = {
        .n = p->n, .x = p->x, .y = p->y, .z = p->z,
        .vx = vel ? p->vx : NULL, .vy = vel ? p->vy : NULL, .vz = vel ? p->vz : NULL,
        .density = fields & LAHAR_PFIELD_DENSITY ? p->rho : NULL,
        .pressure = NULL,
        .phase = fields & LAHAR_PFIELD_PHASE ? p->phase : NULL,
        .id = fields & LAHAR_PFIELD_ID ? p->id : NULL,
        .stress = {NULL, NULL, NULL, NULL, NULL, NULL}, /* soil only, below */
    };
    double flow[LAHAR_FLOW_NVAL];
    if (s->has_flow) {
        sph_inflow_values(&s->flow, p, flow);
        v.inlet = p->inlet;
        v.flow = flow;
    }
    if ((fields & LAHAR_PFIELD_PRESSURE) && s->out_pressure) {
        const sph_params *prm = &s->f.prm;
        for (int64_t i = 0; i < p->n; i++) /* soil (sph_soil.h): the mean stress -tr(sigma)/3 */
            s->out_pressure[i] = p->sig[0] && p->phase[i] == SPH_SOIL_PHASE
                                     ? -(p->sig[0][i] + p->sig[3][i] + p->sig[5][i]) / 3.0
                                     : sph_fluid_pressure(prm, p->rho[i]);
        s->work_output_derived += p->n;
        v.pressure = s->out_pressure;
    }
    if ((fields & LAHAR_PFIELD_STRESS) && p->sig[0])
        for (int a = 0; a < SPH_NSTRESS; a++)
            v.stress[a] = p->sig[a];
    s->last_snapshot = step;
    int rc = lahar_particle_output_snapshot(s->out, step, t, &v);
    /* fixed bodies only: the body snapshot of the same step, as the DEM node would write it */
    if (s->fixed_only && sph_node_fixed_snapshot(s, step, t) != 0)
        rc = -1;
    return rc;
}

/* Mark the last snapshot of the files this node writes (common/io/output.h). */
static void sph_node_mark_last(const sph_node *s, const char *name, const char *text)
{
    lahar_output_mark_last_snapshot(s->ns.output_dir, "particles.h5", name, text);
    if (s->fixed_only)
        lahar_output_mark_last_snapshot(s->ns.output_dir, "bodies.h5", name, text);
}

static int sph_node_wait_stop(sph_node *s)
{
    lahar_link_msg msg;
    for (;;) {
        int rc = lahar_link_wait(s->link, LAHAR_ROLE_COORDINATOR, LAHAR_FRAME_T_MSG_STOP, LAHAR_LINK_ANY_STEP, -1, &msg);
        if (rc == LAHAR_LINK_OK || rc == LAHAR_LINK_LOST || rc == LAHAR_LINK_ERROR)
            return rc;
    }
}

static int sph_node_alloc(sph_node *s)
{
    int n = s->nbody > 0 ? s->nbody : 1;
    s->states = calloc((size_t)n, sizeof *s->states);
    s->l_id = calloc((size_t)n, sizeof *s->l_id);
    s->l_np = calloc((size_t)n, sizeof *s->l_np);
    s->l_force = calloc((size_t)n, sizeof *s->l_force);
    s->l_torque = calloc((size_t)n, sizeof *s->l_torque);
    s->l_pforce = calloc((size_t)n, sizeof *s->l_pforce);
    s->l_ptorque = calloc((size_t)n, sizeof *s->l_ptorque);
    s->l_pcap = 1024;
    s->l_px = calloc((size_t)s->l_pcap, sizeof *s->l_px);
    s->l_pf = calloc((size_t)s->l_pcap, sizeof *s->l_pf);
    if (!s->states || !s->l_id || !s->l_np || !s->l_force || !s->l_torque || !s->l_pforce || !s->l_ptorque ||
        !s->l_px || !s->l_pf)
        return -1;
    for (int i = 0; i < n; i++) {
        s->l_pforce[i] = s->l_force[i];
        s->l_ptorque[i] = s->l_torque[i];
    }
    const lahar_case *c = &s->ns.scene;
    for (int b = 0; b < s->nbody; b++) {
        const lahar_body *bd = &c->bodies[b];
        lahar_body_state *st = &s->states[b];
        memcpy(st->x, bd->x, sizeof st->x);
        memcpy(st->q, bd->q, sizeof st->q);
        if (bd->motion != LAHAR_MOTION_FIXED) {
            memcpy(st->v, bd->v, sizeof st->v);
            memcpy(st->w, bd->w, sizeof st->w);
        }
    }
    return 0;
}

static void sph_node_free(sph_node *s)
{
    lahar_particle_output_close(s->out);
    if (s->fluid_ready)
        sph_fluid_free(&s->f);
    lahar_body_state_buf_free(&s->bodies);
    free(s->states);
    free(s->l_id);
    free(s->l_np);
    free(s->l_force);
    free(s->l_torque);
    free(s->l_pforce);
    free(s->l_ptorque);
    free(s->l_px);
    free(s->l_pf);
    free(s->out_pressure);
    lahar_body_output_close(s->bout);
    lahar_contact_output_close(s->cout);
    lahar_gauge_output_close(s->gauges);
    sph_probes_free(&s->probes);
    sph_inflow_free(&s->flow);
    free(s->reports);
    free(s->c_x);
    free(s->c_f);
    lahar_case_free(&s->ns.scene);
}

/* The region where a body can touch a particle at t_{k+1}: the particles' bounding box at t_k
 * grown by the kernel support (the coupling's range) plus how far a particle can move in a step
 * (CFL keeps it below a fraction of h; twice the support covers it with room to spare). The DEM
 * node sends BODY_STATE only for moving bodies whose bounding sphere reaches into it. */
static void sph_node_reach(const sph_node *s, double lo[3], double hi[3])
{
    const sph_particles *p = &s->f.p;
    const double margin = 2.0 * s->f.k.support;
    for (int a = 0; a < 3; a++) {
        lo[a] = INFINITY;
        hi[a] = -INFINITY;
    }
    /* comparisons, not fmin/fmax calls (libm, 2 % of a 2-thread step serially); NaN is skipped
     * either way */
    for (int64_t i = 0; i < p->n; i++) {
        const double x = p->x[i], y = p->y[i], z = p->z[i];
        lo[0] = x < lo[0] ? x : lo[0], hi[0] = x > hi[0] ? x : hi[0];
        lo[1] = y < lo[1] ? y : lo[1], hi[1] = y > hi[1] ? y : hi[1];
        lo[2] = z < lo[2] ? z : lo[2], hi[2] = z > hi[2] ? z : hi[2];
    }
    for (int a = 0; a < 3; a++) {
        if (s->f.prm.opt.periodic[a]) { /* particles wrap: the whole period, and beyond by the margin */
            lo[a] = fmin(lo[a], s->f.prm.opt.lo[a]);
            hi[a] = fmax(hi[a], s->f.prm.opt.hi[a]);
        }
        lo[a] -= margin;
        hi[a] += margin;
    }
}

/* The rows of LOADS from the coupling's last evaluation (the bodies and particles at t_k): every
 * body with at least one particle within reach; contact points for moving bodies and for bodies
 * marked record_contacts (fixed ones: the resultant only otherwise, for forces.h5). Returns the
 * number of bodies listed (rows in s->l_*; *npoints the points in s->l_px/l_pf), or -1 when
 * out of memory. */
static int sph_node_build_loads(sph_node *s, int64_t *npoints)
{
    const sph_coupling *cp = &s->f.cpl;
    const lahar_case *c = &s->ns.scene;
    int nb = 0;
    int64_t np = 0;
    for (int b = 0; b < s->nbody; b++) {
        int64_t n = cp->body_start[b + 1] - cp->body_start[b];
        if (n == 0)
            continue;
        const lahar_body *bd = &c->bodies[b];
        int points = bd->motion != LAHAR_MOTION_FIXED || bd->record_contacts;
        s->l_id[nb] = b;
        memcpy(s->l_force[nb], cp->force[b], sizeof s->l_force[nb]);
        memcpy(s->l_torque[nb], cp->torque[b], sizeof s->l_torque[nb]);
        s->l_np[nb] = points ? (int32_t)n : 0;
        if (points) {
            if (np + n > s->l_pcap) {
                int64_t cap = s->l_pcap;
                while (cap < np + n)
                    cap *= 2;
                double **px = realloc(s->l_px, (size_t)cap * sizeof *px);
                if (px)
                    s->l_px = px;
                double **pf = px ? realloc(s->l_pf, (size_t)cap * sizeof *pf) : NULL;
                if (!px || !pf)
                    return -1;
                s->l_pf = pf;
                s->l_pcap = cap;
            }
            for (int64_t i = 0; i < n; i++) {
                sph_contact *ct = &cp->contacts[cp->body_start[b] + i];
                s->l_px[np + i] = ct->xs;
                s->l_pf[np + i] = ct->force;
            }
            np += n;
        }
        nb++;
    }
    if (np > INT32_MAX)
        return -1;
    *npoints = np;
    return nb;
}

/* LOADS(k) for the DEM node (sph_node_build_loads). */
static int sph_node_send_loads(sph_node *s, int64_t k)
{
    int64_t np;
    int nb = sph_node_build_loads(s, &np);
    if (nb < 0)
        return -1;
    lahar_loads_t m = {
        .run_id = lahar_link_run_id(s->link), .step = k, .nbody = nb, .body_id = s->l_id, .force = s->l_pforce,
        .torque = s->l_ptorque, .npoints = s->l_np, .ntotal = (int32_t)np, .point_x = s->l_px, .point_f = s->l_pf,
    };
    sph_node_reach(s, m.reach_lo, m.reach_hi);
    int rc;
    LAHAR_LINK_SEND(rc, s->link, LAHAR_FRAME_T_MSG_LOADS, lahar_loads_t, k, &m);
    return rc;
}

/* ---- fixed bodies only: no DEM node ----------------------------------------------------------
 * Bodies that never move need no integration: the coordinator then starts no DEM node (no STEP,
 * STATUS, LOADS or BODY_STATE for it), the coupling uses the scene's poses (it always does for
 * fixed bodies) and this node writes the body files the DEM node would have written, from the
 * same numbers: bodies.h5 (the scene's poses, quaternions normalised as the engine stores them,
 * zero velocities), forces.h5 (per step k the row of t_{k+1} holding the fluid's force at t_k:
 * the resultants LOADS(k) would carry; fixed bodies have no body-body contacts) and contacts.h5
 * (the points of the marked bodies, at the steps that start at an output time). */

static int sph_node_fixed_snapshot(sph_node *s, int64_t step, double t)
{
    const lahar_case *c = &s->ns.scene;
    for (int b = 0; b < s->nbody; b++) {
        lahar_body_state *st = &s->states[b];
        memcpy(st->x, c->bodies[b].x, sizeof st->x);
        q_store(q_normalize(q_load(c->bodies[b].q)), st->q);
        memset(st->v, 0, sizeof st->v);
        memset(st->w, 0, sizeof st->w);
    }
    return lahar_body_output_snapshot(s->bout, step, t, s->states);
}

/* Open the body files and write the snapshot at t = 0. 0, or -1 with a message in err. */
static int sph_node_fixed_open(sph_node *s, char *err, size_t errlen)
{
    const lahar_case *c = &s->ns.scene;
    s->reports = calloc((size_t)s->nbody, sizeof *s->reports);
    if (!s->reports) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    if (!(s->bout = lahar_body_output_open(s->ns.output_dir, c, err, errlen)))
        return -1;
    err[0] = '\0';
    if (!(s->cout = lahar_contact_output_open(s->ns.output_dir, c, err, errlen)) && err[0])
        return -1;
    s->at_output_time = 1; /* t_0 */
    if (c->resume) /* the snapshot of t = 0 is on disk; the checkpoint has the rest */
        return 0;
    if (sph_node_fixed_snapshot(s, 0, 0.0) != 0) {
        snprintf(err, errlen, "cannot write the first body snapshot in %s", s->ns.output_dir);
        lahar_output_explain(err, errlen);
        return -1;
    }
    return 0;
}

/* Step k of the body files, before the particles move: the force row of t_{k+1} and, when step
 * k starts at an output time, contacts.h5 at t_k, both from the coupling at t_k (the numbers of
 * LOADS(k)). 0, or -1 with a message in err. */
static int sph_node_fixed_forces(sph_node *s, int64_t k, const lahar_step_t *step, char *err, size_t errlen)
{
    int64_t np;
    int nb = sph_node_build_loads(s, &np);
    if (nb < 0) {
        snprintf(err, errlen, "out of memory for the body loads");
        return -1;
    }
    memset(s->reports, 0, (size_t)s->nbody * sizeof *s->reports);
    for (int i = 0; i < nb; i++) {
        memcpy(s->reports[s->l_id[i]].force, s->l_force[i], sizeof s->reports[0].force);
        memcpy(s->reports[s->l_id[i]].torque, s->l_torque[i], sizeof s->reports[0].torque);
    }
    if (lahar_body_output_forces(s->bout, k + 1, step->t_next, s->reports) != 0) {
        snprintf(err, errlen, "cannot append to forces.h5 in %s", s->ns.output_dir);
        lahar_output_explain(err, errlen);
        return -1;
    }
    int at_output = s->at_output_time;
    s->at_output_time = step->write_output;
    if (!s->cout || !at_output)
        return 0;
    if (np > s->c_cap) { /* at output times only, and only when more points than ever before */
        int64_t cap = s->c_cap > 0 ? s->c_cap : 1024;
        while (cap < np)
            cap *= 2;
        double(*x)[3] = realloc(s->c_x, (size_t)cap * sizeof *x);
        if (x)
            s->c_x = x;
        double(*f)[3] = x ? realloc(s->c_f, (size_t)cap * sizeof *f) : NULL;
        if (!x || !f) {
            snprintf(err, errlen, "out of memory for %lld contact points", (long long)np);
            return -1;
        }
        s->c_f = f;
        s->c_cap = cap;
    }
    for (int64_t i = 0; i < np; i++) {
        memcpy(s->c_x[i], s->l_px[i], sizeof s->c_x[i]);
        memcpy(s->c_f[i], s->l_pf[i], sizeof s->c_f[i]);
    }
    if (lahar_contact_output_write(s->cout, k, step->t, nb, s->l_id, s->l_np, (const double(*)[3])s->c_x,
                                   (const double(*)[3])s->c_f, (const double(*)[3])s->l_force,
                                   (const double(*)[3])s->l_torque) != 0) {
        snprintf(err, errlen, "cannot write to contacts.h5 in %s", s->ns.output_dir);
        lahar_output_explain(err, errlen);
        return -1;
    }
    return 0;
}

/* Bodies at t_{k+1} from BODY_STATE(k). A moving body the DEM node did not list is out of reach
 * of every particle: it is placed at infinity, where the coupling's distance test skips it (its
 * last known pose may be near the water it has since left). */
static void sph_node_take_states(sph_node *s)
{
    const lahar_case *c = &s->ns.scene;
    for (int b = 0; b < s->nbody; b++)
        if (c->bodies[b].motion != LAHAR_MOTION_FIXED) {
            s->states[b].x[0] = s->states[b].x[1] = s->states[b].x[2] = INFINITY;
        }
    const lahar_body_state_buf *m = &s->bodies;
    for (int i = 0; i < m->n; i++) {
        int b = m->id[i];
        if (b < 0 || b >= s->nbody)
            continue;
        lahar_body_state *st = &s->states[b];
        memcpy(st->x, m->x[i], sizeof st->x);
        memcpy(st->q, m->q[i], sizeof st->q);
        memcpy(st->v, m->v[i], sizeof st->v);
        memcpy(st->w, m->w[i], sizeof st->w);
    }
}

/* Kinetic energy of the fluid (J, J/m in 2D), summed serially: the same bits for any thread count. */
static double sph_node_kinetic_energy(const sph_particles *p)
{
    double e = 0.0;
    for (int64_t i = 0; i < p->n; i++)
        e += 0.5 * p->m[i] * (p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i] + p->vz[i] * p->vz[i]);
    return e;
}

/* The work counters of STATUS (cumulative since set-up; lcm_types/status_t.lcm). Pairs are the
 * solver's neighbour counts halved: every pass visits each pair from both ends (soil-soil: the
 * soil pass; fluid-soil: the soil pass's water neighbours and the seepage pass's soil ones, both
 * only when the soil has k_h > 0, i.e. there is seepage work). */
static void sph_node_work(const sph_node *s, lahar_status_t *st)
{
    st->work_passes = s->f.work_passes;
    st->work_pairs_fluid = s->f.work_neighbours_fluid / 2;
    st->work_pairs_soil = s->f.work_neighbours_soil / 2;
    st->work_pairs_fluid_soil = s->f.work_neighbours_fluid_soil / 2;
    st->work_particle_body = s->work_particle_body;
    st->work_body_body = 0;
    st->work_output_derived = s->work_output_derived;
    if (s->has_flow) /* cumulative, like the work counters; the coordinator's summary.json "flow" */
        sph_inflow_values(&s->flow, &s->f.p, st->flow);
}

/* After every evaluation of the coupling: its contacts join the particle-body work. */
static void sph_node_count_coupling(sph_node *s)
{
    if (s->f.has_bodies)
        s->work_particle_body += s->f.cpl.ncontacts;
}

static void sph_node_crossing_message(const sph_node *s, int64_t k, double t, char *err, size_t n)
{
    const sph_coupling *cp = &s->f.cpl;
    int b = cp->cross_body;
    if (k < 0) {
        snprintf(err, n, "particle %lld starts inside body %d '%s' (%.3g m inside the surface; %lld particle%s "
                 "inside bodies at t = 0): move the particle block or the body",
                 (long long)cp->cross_particle_id, b, b >= 0 && b < s->nbody ? s->ns.scene.bodies[b].name : "?",
                 cp->cross_depth, (long long)cp->crossings, cp->crossings == 1 ? "" : "s");
        return;
    }
    snprintf(err, n,
             "particle %lld crossed the surface of body %d '%s' in step %lld (t = %.9g s; %.3g m inside; %lld "
             "particle%s inside bodies); the last snapshot is the state after that step",
             (long long)cp->cross_particle_id, b, b >= 0 && b < s->nbody ? s->ns.scene.bodies[b].name : "?",
             (long long)k, t, cp->cross_depth, (long long)cp->crossings, cp->crossings == 1 ? "" : "s");
}

/* Position of the particle with this id (a search: only after a failure), 0 if found. */
static int sph_node_find_particle(const sph_particles *p, int64_t id, double x[3])
{
    for (int64_t i = 0; i < p->n; i++)
        if (p->id[i] == id) {
            x[0] = p->x[i], x[1] = p->y[i], x[2] = p->z[i];
            return 0;
        }
    x[0] = x[1] = x[2] = NAN;
    return -1;
}

/* The crossing of step k (sph_node_crossing_message) as an instability report. */
static void sph_node_crossing_report(const sph_node *s, int64_t k, double t, lahar_instability *u)
{
    const sph_coupling *cp = &s->f.cpl;
    int b = cp->cross_body;
    memset(u, 0, sizeof *u);
    snprintf(u->what, sizeof u->what, "crossing");
    snprintf(u->kind, sizeof u->kind, "particle");
    u->id = cp->cross_particle_id;
    snprintf(u->name, sizeof u->name, "%s", b >= 0 && b < s->nbody ? s->ns.scene.bodies[b].name : "?");
    sph_node_find_particle(&s->f.p, u->id, u->x);
    u->step = k;
    u->t = t;
    u->value = cp->cross_depth;
    u->limit = 0.0;
    sph_node_crossing_message(s, k, t, u->text, sizeof u->text);
}

/* The particle checks of common/protocol/instability.h on the state after step k (time t): every
 * position, velocity and density finite, and rho / rho0 within stability.density_band. One
 * streaming pass counts the failures (a sum: the same for any thread count); only when there are
 * some, a serial pass names the worst: the non-finite particle of lowest id, else the one
 * farthest outside the band (largest |ln(rho / rho0)|, lowest id on a tie). Returns the count. */
static int64_t sph_node_check_particles(const sph_node *s, int64_t k, double t, lahar_instability *u)
{
    const sph_particles *p = &s->f.p;
    const int64_t n = p->n;
    const double rho_water = s->ns.scene.sph_density;
    const double *band = s->ns.scene.stability.density_band;
    /* rho0 of particle I and the band's lower end: the water's; soil particles (sph_soil.h) have
     * their material's rest density and no lower end: their density comes from continuity and
     * thins where the soil spreads or separates (physical for a granular material, and there is no
     * EOS to turn it into a pressure), but a soil particle squeezed to band[1] x its rest density is
     * an impact the step did not resolve (a 2D block into a wall at 20 m/s reached 5.6 x) */
    const double rho_soil = s->f.has_soil ? s->f.soil.mat.density : NAN;
#define SPH_NODE_SOIL(I) (s->f.has_soil && p->phase[I] == SPH_SOIL_PHASE)
#define SPH_NODE_RHO0(I) (SPH_NODE_SOIL(I) ? rho_soil : rho_water)
#define SPH_NODE_IN_BAND(I) \
    ((SPH_NODE_SOIL(I) || p->rho[I] >= band[0] * SPH_NODE_RHO0(I)) && p->rho[I] <= band[1] * SPH_NODE_RHO0(I))
    int64_t bad = 0;
#pragma omp parallel for schedule(static) reduction(+ : bad) if (n >= SPH_OMP_MIN_LIGHT)
    for (int64_t i = 0; i < n; i++) {
        /* a NaN or an infinity in any component makes the sum non-finite; a NaN density fails
         * the band test too */
        double sum = p->x[i] + p->y[i] + p->z[i] + p->vx[i] + p->vy[i] + p->vz[i];
        bad += !(isfinite(sum) && isfinite(p->rho[i]) && SPH_NODE_IN_BAND(i));
    }
    if (bad == 0)
        return 0;
    int64_t worst = -1, worst_nf = -1;
    double dev_max = -1.0;
    for (int64_t i = 0; i < n; i++) {
        double sum = p->x[i] + p->y[i] + p->z[i] + p->vx[i] + p->vy[i] + p->vz[i];
        if (!isfinite(sum) || !isfinite(p->rho[i])) {
            if (worst_nf < 0 || p->id[i] < p->id[worst_nf])
                worst_nf = i;
        } else if (!SPH_NODE_IN_BAND(i)) {
            double dev = fabs(log(p->rho[i] / SPH_NODE_RHO0(i)));
            if (dev > dev_max || (dev == dev_max && p->id[i] < p->id[worst])) {
                dev_max = dev;
                worst = i;
            }
        }
    }
    int64_t i = worst_nf >= 0 ? worst_nf : worst;
    memset(u, 0, sizeof *u);
    snprintf(u->kind, sizeof u->kind, "particle");
    u->id = p->id[i];
    u->x[0] = p->x[i], u->x[1] = p->y[i], u->x[2] = p->z[i];
    u->step = k;
    u->t = t;
    const double r = p->rho[i] / SPH_NODE_RHO0(i);
    const int soil = SPH_NODE_SOIL(i);
#undef SPH_NODE_IN_BAND
#undef SPH_NODE_RHO0
#undef SPH_NODE_SOIL
    if (worst_nf >= 0) {
        snprintf(u->what, sizeof u->what, "non-finite state");
        u->value = NAN;
        u->limit = NAN;
        snprintf(u->text, sizeof u->text,
                 "particle %lld has a non-finite state after step %lld (t = %.9g s): x = (%.4g, %.4g, %.4g) m, "
                 "v = (%.3g, %.3g, %.3g) m/s, rho/rho0 = %.4g; %lld particle%s failed the checks; the last snapshot is "
                 "that state",
                 (long long)u->id, (long long)k, t, p->x[i], p->y[i], p->z[i], p->vx[i], p->vy[i], p->vz[i], r,
                 (long long)bad, bad == 1 ? "" : "s");
    } else {
        snprintf(u->what, sizeof u->what, "density out of band");
        u->value = r;
        u->limit = r < band[0] ? band[0] : band[1];
        snprintf(u->text, sizeof u->text,
                 "%s particle %lld at (%.4g, %.4g, %.4g) m has rho/rho0 = %.4g outside stability.density_band [%g, %g]%s "
                 "after step %lld (t = %.9g s); %lld particle%s outside; the last snapshot is that state",
                 soil ? "soil" : "water", (long long)u->id, u->x[0], u->x[1], u->x[2], r, band[0], band[1],
                 soil ? " (soil: its upper end only)" : "", (long long)k, t, (long long)bad, bad == 1 ? "" : "s");
    }
    return bad;
}

/* The coordinator stopped the run before step k (the particles are at the end of step k - 1,
 * time t): on a stop for an error (another node's instability, a time step collapse) the state
 * reached is written as the final snapshot, marked with the coordinator's reason, unless a
 * snapshot of it exists. */
static void sph_node_final_snapshot(sph_node *s, const lahar_link_msg *stop, int64_t k, double t)
{
    char why[512];
    int reason = lahar_node_stop_reason(stop, why, sizeof why);
    if (reason <= 0 || s->f.begun)
        return;
    if (s->last_snapshot != k && sph_node_snapshot(s, k, t) != 0)
        return;
    sph_node_mark_last(s, "stopped", why);
}

/* STOP came while the node waited for BODY_STATE(k) after sph_fluid_step_begin (typically: the
 * DEM node died): the particles are drifted but not kicked, a state of no time. On a stop for an
 * error the step is finished with the moving bodies where the last BODY_STATE put them (t_k) and
 * that state is written as the final snapshot of t_{k+1}, marked `stopped` with the coordinator's
 * reason and that caveat, so the run's particle file ends where the run ended (lcm_types/README.md). */
static void sph_node_stopped_half_step(sph_node *s, const lahar_link_msg *stop, int64_t k, const lahar_step_t *step)
{
    char why[512], mark[768];
    if (lahar_node_stop_reason(stop, why, sizeof why) <= 0)
        return;
    if (sph_fluid_step_end(&s->f, step->dt, s->states) < 0 || sph_node_snapshot(s, k + 1, step->t_next) != 0)
        return;
    snprintf(mark, sizeof mark, "%s (step %lld finished with the moving bodies at their state of t = %.9g s: no "
             "BODY_STATE came for it)", why, (long long)k, step->t);
    sph_node_mark_last(s, "stopped", mark);
}

/* Pressure probes (sph_probes.h): set up, and the sample of t = 0. Nothing without probes. */
static int sph_node_probes_open(sph_node *s, char *err, size_t errlen)
{
    const lahar_case *c = &s->ns.scene;
    if (c->nprobe <= 0)
        return 0;
    if (sph_probes_init(&s->probes, c) != 0) {
        snprintf(err, errlen, "out of memory for the probes");
        return -1;
    }
    if (!(s->gauges = lahar_gauge_output_open(s->ns.output_dir, c, err, errlen)))
        return -1;
    if (c->resume) /* the sample of t = 0 is on disk */
        return 0;
    sph_probes_sample(&s->probes, &s->f, c, s->nbody > 0 ? s->states : NULL, 0.0);
    if (lahar_gauge_output_write(s->gauges, 0, 0.0, s->probes.value, s->probes.due) != 0) {
        snprintf(err, errlen, "cannot write gauges.h5 in %s", s->ns.output_dir);
        lahar_output_explain(err, errlen);
        return -1;
    }
    return 0;
}

/* The probes due at the state of step k + 1 (time t). 0 or -1 (gauges.h5 not written). */
static int sph_node_probes_sample(sph_node *s, int64_t k, double t)
{
    if (!s->gauges)
        return 0;
    if (sph_probes_sample(&s->probes, &s->f, &s->ns.scene, s->nbody > 0 ? s->states : NULL, t) == 0)
        return 0;
    return lahar_gauge_output_write(s->gauges, k + 1, t, s->probes.value, s->probes.due);
}

/* ---- checkpoints (common/io/checkpoint.h) -------------------------------------------------------
 * Everything step k + 1 reads of the state after step k, in the particles' current (sorted)
 * order: the particle arrays (incl. the rates of the last evaluation, which the first kick of
 * the next step uses, and the soil's stress and stress rate), the solver's counters (step: the
 * Shepard filter's period), the transport velocity's b, the coupling's forces and contact points
 * of the last evaluation (LOADS of the next step) and the soil-DEM friction springs, the body
 * states the coupling uses, the probes' sampling slots and this node's own counters. Buffers
 * that every evaluation refills before reading (cells, EOS terms, SPS stress, soil pass
 * scratch) are not stored. One function both ways: 0, or -1 with the message in f->err. */
_Static_assert(sizeof(int) == sizeof(int32_t), "soil_hist_body is stored as int32");

static void sph_node_io_f64(lahar_ckpt_file *f, const char *name, double *a, int64_t n)
{
    if (a)
        lahar_ckpt_f64(f, name, a, n);
}

/* The step, time and particle count; reading, the count must fit this case (open boundaries: up to
 * its capacity; else exactly its count). */
static int64_t sph_state_io_count(sph_node *s, lahar_ckpt_file *f, int64_t *k, double *t_now)
{
    sph_particles *p = &s->f.p;
    lahar_ckpt_i64(f, "step", k, 1);
    lahar_ckpt_f64(f, "t", t_now, 1);
    int64_t n = p->n;
    lahar_ckpt_i64(f, "n", &n, 1);
    if (s->has_flow && !f->writing && !f->failed) {
        if (n < 0 || n > p->cap) {
            snprintf(f->err, sizeof f->err, "the checkpoint holds %lld particles, this case has room for %lld "
                     "(another case?)", (long long)n, (long long)p->cap);
            f->failed = 1;
        } else {
            p->n = n;
        }
    } else if (!f->writing && !f->failed && n != p->n) {
        snprintf(f->err, sizeof f->err, "the checkpoint holds %lld particles, this case fills %lld (another case?)",
                 (long long)n, (long long)p->n);
        f->failed = 1;
    }
    return n;
}

/* Every per-particle array the next step reads: state, half-step values, soil stresses and their
 * rates, the transport velocity's terms. */
static void sph_state_io_particles(sph_node *s, lahar_ckpt_file *f, int64_t n)
{
    sph_fluid *fl = &s->f;
    sph_particles *p = &fl->p;
    static const char *const names[] = {"x", "y", "z", "vx", "vy", "vz", "rho", "p", "m", "ax", "ay", "az", "drho",
                                        "vhx", "vhy", "vhz", "rhoh", "tvx", "tvy", "tvz"};
    double *arrays[] = {p->x, p->y, p->z, p->vx, p->vy, p->vz, p->rho, p->p, p->m, p->ax, p->ay, p->az, p->drho,
                        p->vhx, p->vhy, p->vhz, p->rhoh, p->tvx, p->tvy, p->tvz};
    for (size_t a = 0; a < sizeof names / sizeof names[0]; a++)
        sph_node_io_f64(f, names[a], arrays[a], n);
    lahar_ckpt_i32(f, "phase", p->phase, n);
    lahar_ckpt_i64(f, "id", p->id, n);
    char name[32];
    for (int a = 0; a < SPH_NSTRESS; a++) {
        snprintf(name, sizeof name, "sig%d", a);
        sph_node_io_f64(f, name, p->sig[a], n);
        snprintf(name, sizeof name, "sigh%d", a);
        sph_node_io_f64(f, name, p->sigh[a], n);
        if (fl->has_soil) {
            snprintf(name, sizeof name, "dsig%d", a);
            sph_node_io_f64(f, name, fl->soil.dsig[a], n);
        }
    }
    sph_node_io_f64(f, "tv_bx", fl->tv_bx, n);
    sph_node_io_f64(f, "tv_by", fl->tv_by, n);
    sph_node_io_f64(f, "tv_bz", fl->tv_bz, n);
}

/* The solver's clock and step-size inputs, the work counters, the summary figures and the bodies'
 * states. */
static void sph_state_io_solver(sph_node *s, lahar_ckpt_file *f)
{
    sph_fluid *fl = &s->f;
    lahar_ckpt_f64(f, "fluid_t", &fl->t, 1);
    lahar_ckpt_i64(f, "fluid_step", &fl->step, 1);
    lahar_ckpt_f64(f, "vmax", &fl->vmax, 1);
    lahar_ckpt_f64(f, "amax", &fl->amax, 1);
    lahar_ckpt_f64(f, "nut_max", &fl->nut_max, 1);
    lahar_ckpt_i64(f, "crossings", &fl->crossings, 1);
    int64_t work[] = {fl->work_passes, fl->work_neighbours_fluid, fl->work_neighbours_soil,
                      fl->work_neighbours_fluid_soil, s->work_particle_body, s->work_output_derived, s->last_snapshot};
    lahar_ckpt_i64(f, "counters", work, 7);
    if (!f->writing && !f->failed) {
        fl->work_passes = work[0], fl->work_neighbours_fluid = work[1], fl->work_neighbours_soil = work[2];
        fl->work_neighbours_fluid_soil = work[3], s->work_particle_body = work[4], s->work_output_derived = work[5];
        s->last_snapshot = work[6];
    }
    lahar_ckpt_int(f, "at_output_time", &s->at_output_time);
    lahar_ckpt_f64(f, "kinetic_energy", &s->kinetic_energy, 1);
    if (s->nbody > 0)
        lahar_ckpt_f64(f, "body_states", (double *)s->states, (int64_t)s->nbody * 13);
}

/* The coupling's last evaluation (the loads the DEM node gets next) and the soil springs. */
static void sph_state_io_coupling(sph_coupling *c, lahar_ckpt_file *f)
{
    lahar_ckpt_f64(f, "cpl_force", (double *)c->force, (int64_t)c->nbody * 3);
    lahar_ckpt_f64(f, "cpl_torque", (double *)c->torque, (int64_t)c->nbody * 3);
    lahar_ckpt_i64(f, "cpl_body_start", c->body_start, c->nbody + 1);
    lahar_ckpt_f64(f, "cpl_kn", &c->kn, 1);
    int64_t nc = c->ncontacts;
    lahar_ckpt_i64(f, "cpl_ncontacts", &nc, 1);
    if (!f->writing && !f->failed && nc > c->contacts_cap) {
        sph_contact *m = realloc(c->contacts, (size_t)nc * sizeof *m);
        if (!m) {
            snprintf(f->err, sizeof f->err, "out of memory for %lld contacts", (long long)nc);
            f->failed = 1;
        } else {
            c->contacts = m;
            c->contacts_cap = nc;
        }
    }
    if (!f->failed) {
        c->ncontacts = nc;
        /* sph_contact is doubles and an int64: stored as the bytes of the array */
        void *blob = c->contacts;
        size_t len = (size_t)nc * sizeof *c->contacts;
        if (f->writing) {
            lahar_ckpt_blob(f, "cpl_contacts", &blob, &len);
        } else {
            lahar_ckpt_u8(f, "cpl_contacts", blob, (int64_t)len);
        }
    }
    if (c->soil_hist_body) {
        const int64_t nh = c->pcap * SPH_COUPLING_MAX_PER_PARTICLE;
        lahar_ckpt_i32(f, "cpl_soil_hist_body", (int32_t *)c->soil_hist_body, nh);
        lahar_ckpt_f64(f, "cpl_soil_hist_d", (double *)c->soil_hist_d, nh * 3);
    }
    c->near_valid = 0;
}

static int sph_node_state_io(sph_node *s, lahar_ckpt_file *f, int64_t *k, double *t_now)
{
    const int64_t n = sph_state_io_count(s, f, k, t_now);
    sph_state_io_particles(s, f, n);
    sph_state_io_solver(s, f);
    if (s->f.has_bodies)
        sph_state_io_coupling(&s->f.cpl, f);
    if (s->probes.n > 0) {
        lahar_ckpt_i64(f, "probe_next_slot", s->probes.next_slot, s->probes.n);
        lahar_ckpt_i64(f, "probe_target", s->probes.target, s->probes.n); /* trackers' particles */
    }
    if (s->has_flow)
        sph_inflow_state_io(&s->flow, &s->f.p, f);
    return f->failed ? -1 : 0;
}

/* Step k done (the state of step index k + 1 at t): flush the streams and write
 * OUT/checkpoints/NNNNNN.tmp/sph.h5, synced. 0, or -1 with a message in err. */
static int sph_node_checkpoint(sph_node *s, int64_t state_step, double t, char *err, size_t errlen)
{
    char dir[1200], path[1300];
    lahar_ckpt_dir(dir, sizeof dir, s->ns.output_dir, state_step, 1);
    snprintf(path, sizeof path, "%s/sph.h5", dir);
    if (lahar_body_output_sync(s->bout) != 0 || lahar_gauge_output_sync(s->gauges) != 0 ||
        lahar_mkdir_p(dir) != 0) {
        snprintf(err, errlen, "cannot write the checkpoint in %s", dir);
        return -1;
    }
    lahar_ckpt_file f;
    int64_t k = state_step;
    double tt = t;
    if (lahar_ckpt_create(&f, path, "sph") == 0)
        sph_node_state_io(s, &f, &k, &tt);
    if (lahar_ckpt_close(&f) != 0) {
        snprintf(err, errlen, "%s", f.err);
        return -1;
    }
    return 0;
}

/* One step of sph_node_loop as its phases see it: what they did, and the first failure. */
typedef struct {
    lahar_status_t st; /* the STATUS sent at the end of the step; st.error: the step failed */
    char err[2048];    /* why, when st.error */
    int begun;         /* sph_fluid_step_begin ran: the particles have drifted */
    int stepped;       /* ... and sph_fluid_step_end: the state is t_{k+1} */
    int unstable;      /* a stability check failed; u says which */
    lahar_instability u;
} sph_step;

/* The first half of step k, which needs no body states: done before waiting for them, so the DEM
 * node's advance and the BODY_STATE latency hide behind it. At k = 0 the rates at t_0 with K_n of
 * the first step (eq. 15 depends on dt); without bodies the rates of the set-up do not depend on
 * dt and stand. Then the loads to the DEM node (or the forces on fixed bodies), the inflow and the
 * drift. */
static void sph_step_first_half(sph_node *s, int64_t k, const lahar_step_t *step, int has_dem, sph_step *w)
{
    if (k == 0 && s->f.has_bodies) {
        int64_t cross = sph_fluid_rates(&s->f, has_dem ? s->states : NULL, step->dt);
        sph_node_count_coupling(s);
        if (cross < 0) {
            w->st.error = 1;
            lahar_errf(w->err, sizeof w->err, "out of memory in the SPH rates");
        } else if (cross > 0) {
            w->st.error = 1;
            sph_node_crossing_message(s, -1, 0.0, w->err, sizeof w->err);
        }
    }
    if (has_dem && sph_node_send_loads(s, k) != 0 && !w->st.error) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "cannot send LOADS(%lld) (out of memory)", (long long)k);
    } else if (s->fixed_only && !w->st.error && sph_node_fixed_forces(s, k, step, w->err, sizeof w->err) != 0) {
        w->st.error = 1;
    }
    if (!w->st.error && s->has_flow &&
        sph_inflow_apply(&s->flow, &s->f, step->t, step->dt, w->err, (int)sizeof w->err) == INT64_MIN)
        w->st.error = 1;
    if (w->st.error)
        return;
    if (sph_fluid_step_begin(&s->f, step->dt) != 0) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "out of memory in the SPH step");
    } else {
        w->begun = 1;
    }
}

/* The moving bodies at t_{k+1}, after the DEM node's advance with LOADS(k). Returns -1 to go on
 * (w->st.error set if the message was bad), else the node's exit status: 0 when the coordinator
 * stopped the run, 3 when the link was lost. */
static int sph_step_wait_bodies(sph_node *s, int64_t k, const lahar_step_t *step, sph_step *w)
{
    lahar_link_msg msg;
    int rc = lahar_link_wait(s->link, LAHAR_ROLE_DEM, LAHAR_FRAME_T_MSG_BODY_STATE, k, -1, &msg);
    if (rc == LAHAR_LINK_STOP) {
        if (w->begun)
            sph_node_stopped_half_step(s, &msg, k, step);
        return 0;
    }
    if (rc == LAHAR_LINK_LOST)
        return 3;
    if (rc != LAHAR_LINK_OK || lahar_body_state_decode(msg.data, msg.size, &s->bodies) != 0) {
        if (!w->st.error)
            snprintf(w->err, sizeof w->err, "undecodable BODY_STATE(%lld)", (long long)k);
        w->st.error = 1;
    } else {
        sph_node_take_states(s);
    }
    return -1;
}

/* The second half: the kick with the body states, then the checks of the new state (a body
 * crossed, the stability checks) and the probes at t_{k+1}. A failed BODY_STATE after step_begin
 * leaves the particles drifted but not kicked: that state is neither t_k nor t_{k+1}, so the step
 * is not taken (stepped stays 0) and no snapshot is written for it (sph_step_output). */
static void sph_step_second_half(sph_node *s, int64_t k, const lahar_step_t *step, int has_dem, sph_step *w)
{
    w->stepped = w->begun && !w->st.error;
    if (!w->stepped)
        return;
    int64_t cross = sph_fluid_step_end(&s->f, step->dt, has_dem ? s->states : NULL);
    sph_node_count_coupling(s);
    if (cross < 0) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "out of memory in the SPH step");
    } else if (cross > 0) {
        sph_node_crossing_report(s, k, step->t_next, &w->u);
        w->unstable = 1;
    } else {
        w->unstable = sph_node_check_particles(s, k, step->t_next, &w->u) > 0;
    }
    if (w->unstable) {
        w->st.error = 1;
        lahar_instability_encode(&w->u, w->err, sizeof w->err);
    } else if (!w->st.error && sph_node_probes_sample(s, k, step->t_next) != 0) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "cannot write gauges.h5 in %s", s->ns.output_dir);
        lahar_output_explain(w->err, sizeof w->err);
    }
}

/* What the step leaves: the snapshot, the STATUS figures and the checkpoint. On an error the state
 * reached is kept as the last snapshot to look at: after the step, or at t_k when the step was not
 * taken (unless a snapshot of t_k exists). */
static void sph_step_output(sph_node *s, int64_t k, const lahar_step_t *step, sph_step *w)
{
    if (w->stepped && (step->write_output || w->st.error) && sph_node_snapshot(s, k + 1, step->t_next) != 0 &&
        !w->st.error) {
        w->st.error = 1;
        lahar_errf(w->err, sizeof w->err, "cannot write a snapshot in %s", s->ns.output_dir);
        lahar_output_explain(w->err, sizeof w->err);
    } else if (!w->stepped && !w->begun && s->last_snapshot != k) {
        sph_node_snapshot(s, k, step->t);
    }
    if (w->unstable && s->last_snapshot == k + 1)
        sph_node_mark_last(s, "instability", w->u.text);
    w->st.dt_proposed = sph_fluid_dt(&s->f);
    w->st.dt_stable = w->st.dt_proposed;
    w->st.ncontacts = s->f.has_bodies ? (int32_t)s->f.cpl.ncontacts : 0;
    /* the kinetic energy is a summary figure (the coordinator keeps the last one): computed at the
     * output times (the last step is one) and on an error, not every step */
    if (step->write_output || w->st.error)
        s->kinetic_energy = sph_node_kinetic_energy(&s->f.p);
    w->st.kinetic_energy = s->kinetic_energy;
    sph_node_work(s, &w->st);
    if (step->checkpoint && !w->st.error) {
        if (sph_node_checkpoint(s, k + 1, step->t_next, w->err, sizeof w->err) == 0)
            w->st.checkpointed = 1;
        else
            w->st.error = 1;
    }
}

/* The steps from k0 (the state at t0) until the coordinator stops the run: the node's exit status. */
static int sph_node_loop(sph_node *s, int64_t k0, double t0)
{
    const int has_dem = s->ns.has_dem && s->nbody > 0;
    double t_now = t0; /* time of the state: the end of the last step taken */
    for (int64_t k = k0;; k++) {
        double wait0 = lahar_link_wait_seconds(s->link);
        lahar_link_msg msg;
        lahar_step_t step;
        int rc = lahar_node_wait_step(s->link, "lahar-sph", k, &msg, &step);
        if (rc == 0)
            sph_node_final_snapshot(s, &msg, k, t_now);
        if (rc >= 0)
            return rc;
        sph_step w = {.st = {0}};
        double c0 = lahar_now();
        sph_step_first_half(s, k, &step, has_dem, &w);
        double compute = lahar_now() - c0;
        if (has_dem && s->nmoving > 0 && (rc = sph_step_wait_bodies(s, k, &step, &w)) >= 0)
            return rc;
        c0 = lahar_now();
        sph_step_second_half(s, k, &step, has_dem, &w);
        sph_step_output(s, k, &step, &w);
        compute += lahar_now() - c0;
        w.st.compute_s = compute;
        w.st.wait_s = lahar_link_wait_seconds(s->link) - wait0;
        lahar_node_send_status(s->link, ROLE, k, &w.st, w.err);
        if (w.st.error) {
            fprintf(stderr, "lahar-sph: step %lld: %s%s\n", (long long)k, w.unstable ? "unstable: " : "",
                    w.unstable ? w.u.text : w.err);
            sph_node_wait_stop(s);
            return 1;
        }
        lahar_link_set_step(s->link, k);
        t_now = step.t_next;
    }
}

/* Build the solver from the scene: parameters, particles of every block, the bodies. */
static int sph_node_setup(sph_node *s, char *err, size_t errlen)
{
    const lahar_case *c = &s->ns.scene;
    sph_params prm;
    if (!(c->sph_dx > 0.0)) {
        snprintf(err, errlen, "the particle spacing sph.dx must be > 0 (got %g)", c->sph_dx);
        return -1;
    }
    if (lahar_sph_node_params(c, &prm, err, errlen) != 0)
        return -1;
    int64_t total = sph_node_count(c), room = 0;
    if (sph_inflow_case_wanted(c)) {
        s->has_flow = 1;
        if (sph_inflow_setup_case(&s->flow, c, &prm, err, (int)errlen) != 0)
            return -1;
        room = sph_inflow_capacity(&s->flow); /* what the inlets may add */
    }
    if (sph_fluid_init(&s->f, &prm, total + room > 0 ? total + room : 1, err, (int)errlen) != 0)
        return -1;
    s->fluid_ready = 1;
    if (total < 0 || sph_node_add_blocks(&s->f.p, c) != 0) {
        snprintf(err, errlen, "out of memory for %lld particles", (long long)total);
        return -1;
    }
    if (s->has_flow && sph_inflow_start(&s->flow, &s->f, 0.0, err, (int)errlen) != 0)
        return -1;
    if (sph_node_alloc(s) != 0) {
        snprintf(err, errlen, "out of memory");
        return -1;
    }
    if (s->nbody > 0 && sph_fluid_attach_bodies(&s->f, s->nbody, c->bodies) != 0) {
        snprintf(err, errlen, "out of memory for the coupling");
        return -1;
    }
    if (sph_cells_sort(&s->f.cells, &s->f.p) != 0) {
        snprintf(err, errlen, "out of memory for the cell lists");
        return -1;
    }
    /* rates at t_0 for the first dt proposal (with K_n of a CFL step; step 0 re-evaluates them
     * with the granted dt) */
    double dt_guess = prm.opt.cfl * s->f.k.h / prm.opt.c0;
    if (sph_fluid_rates(&s->f, s->nbody > 0 ? s->states : NULL, dt_guess) < 0) {
        snprintf(err, errlen, "out of memory in the SPH rates");
        return -1;
    }
    sph_node_count_coupling(s);
    /* the snapshot pressure (sph_node_snapshot) has a buffer only when the case writes it */
    if ((c->output_fields & LAHAR_PFIELD_PRESSURE) && !(s->out_pressure = malloc((size_t)s->f.p.cap * sizeof(double)))) {
        snprintf(err, errlen, "out of memory for %lld particles", (long long)s->f.p.cap);
        return -1;
    }
    return 0;
}

/* Without a DEM node in the run (the coordinator starts none when every body is fixed), this
 * node writes the body files itself; a moving body without a DEM node cannot be integrated. */
static int sph_node_setup_bodies(sph_node *s, char *err, size_t errlen)
{
    const lahar_case *c = &s->ns.scene;
    if (s->ns.has_dem || s->nbody == 0)
        return 0;
    for (int b = 0; b < s->nbody; b++)
        if (c->bodies[b].motion != LAHAR_MOTION_FIXED) {
            snprintf(err, errlen, "body %d '%s' moves, but the run has no DEM node to integrate it", b, c->bodies[b].name);
            return -1;
        }
    s->fixed_only = 1;
    return sph_node_fixed_open(s, err, errlen);
}

int lahar_sph_node_run(const lahar_sph_node_options *o)
{
    char err[2048];
    sph_node s;
    memset(&s, 0, sizeof s);
    unsigned want = LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_HELLO) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_SCENE) |
                    LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STEP) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_BODY_STATE) |
                    LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STOP);
    lahar_transport *t;
    if (lahar_node_connect(o, "lahar-sph", ROLE, want, &t, &s.link) != 0)
        return 2;
    static const char *const caps[] = {"dim2", "dim3", "gravity", "wcsph", "coupling"};
    int status = 0;
    int rc = lahar_node_join(s.link, ROLE, "lahar-sph/wcsph", LAHAR_VERSION, caps, 5,
                             o->join_wait_s > 0 ? o->join_wait_s : 30.0, &s.ns, err, sizeof err);
    if (rc == LAHAR_LINK_STOP)
        goto done;
    if (rc != LAHAR_LINK_OK) {
        fprintf(stderr, "lahar-sph: %s\n", err);
        status = rc == LAHAR_LINK_LOST ? 3 : 2;
        goto done;
    }
    const lahar_case *c = &s.ns.scene;
    s.nbody = c->nbody;
    for (int i = 0; i < c->nbody; i++)
        s.nmoving += c->bodies[i].motion != LAHAR_MOTION_FIXED;
    lahar_status_t st = {0};
    int64_t k0 = 0;
    double t0 = 0.0;
    err[0] = '\0';
    if (sph_node_setup(&s, err, sizeof err) != 0)
        ;
    else if (!(s.out = lahar_particle_output_open(s.ns.output_dir, c, c->output_fields, err, sizeof err)))
        ;
    else if (!c->resume && sph_node_snapshot(&s, 0, 0.0) != 0) {
        snprintf(err, sizeof err, "cannot write the first particle snapshot in %s", s.ns.output_dir);
        lahar_output_explain(err, sizeof err);
    } else if (sph_node_setup_bodies(&s, err, sizeof err) != 0) {
        /* the message is in err */
    } else if (sph_node_probes_open(&s, err, sizeof err) != 0) {
        /* the message is in err */
    } else if (c->resume) {
        /* lahar resume: the state of the checkpoint replaces the initial one set up above */
        char path[1300];
        snprintf(path, sizeof path, "%s/sph.h5", c->resume_dir);
        lahar_ckpt_file f;
        if (lahar_ckpt_open(&f, path, "sph") == 0)
            sph_node_state_io(&s, &f, &k0, &t0);
        if (lahar_ckpt_close(&f) != 0)
            snprintf(err, sizeof err, "%s", f.err);
        else if (k0 != c->resume_step)
            snprintf(err, sizeof err, "%s holds step %lld, the coordinator resumes step %lld", path, (long long)k0,
                     (long long)c->resume_step);
    }
    char desc[256];
    if (s.fluid_ready)
        snprintf(desc, sizeof desc, "WCSPH, %lld particles, kernel %s, h = %g m, c0 = %g m/s, %d bodies coupled%s%s",
                 (long long)s.f.p.n, s.f.prm.opt.kernel, s.f.k.h, s.f.prm.opt.c0, s.nbody,
                 s.f.prm.opt.sps ? ", SPS turbulence" : "", s.f.has_soil ? ", Drucker-Prager soil" : "");
    st.error = err[0] != '\0';
    st.dt_proposed = st.error ? 0.0 : sph_fluid_dt(&s.f);
    st.dt_stable = st.dt_proposed;
    s.kinetic_energy = st.error ? 0.0 : sph_node_kinetic_energy(&s.f.p);
    st.kinetic_energy = s.kinetic_energy;
    if (s.fluid_ready)
        sph_node_work(&s, &st);
    lahar_node_send_status(s.link, ROLE, -1, &st, st.error ? err : desc);
    if (st.error) {
        fprintf(stderr, "lahar-sph: %s\n", err);
        sph_node_wait_stop(&s);
        status = 1;
        goto done;
    }
    status = sph_node_loop(&s, k0, t0);
done:
    lahar_link_heartbeat_stop(s.link);
    sph_node_free(&s);
    lahar_link_destroy(s.link);
    lahar_transport_close(t);
    return status;
}
