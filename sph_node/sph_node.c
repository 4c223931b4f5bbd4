/* SPH node loop (see sph_node.h). Per step k:
 *   wait STEP(k) -> [DEM node present and moving bodies, k > 0: wait BODY_STATE(k-1), the body
 *   states at t_k] -> particle work -> [DEM node present: publish LOADS(k)] -> integrate
 *   -> output -> STATUS(k) with the proposed dt for step k+1.
 * No particle forces yet, so LOADS carry no bodies; the exchange is already in place so the
 * coupling (paper 000 eq. 12-14) only has to fill them. */
#include "sph_node.h"
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "case.h"
#include "lahar_body_state_t.h"
#include "lahar_loads_t.h"
#include "lahar_step_t.h"
#include "link.h"
#include "output.h"
#include "scene_msg.h"
#include "transport.h"

#define ROLE LAHAR_ROLE_SPH

/* Particles a block holds (the lattice of sph_particles_add_box), to size the arrays once. */
static int64_t sph_node_block_count(int dim, double dx, const lahar_particle_block *b)
{
    int64_t count = 1;
    for (int a = 0; a < (dim == 2 ? 2 : 3); a++) {
        int64_t n = (int64_t)floor((b->hi[a] - b->lo[a]) / dx + 1e-9);
        count *= n > 0 ? n : 0;
    }
    return count;
}

int64_t lahar_sph_node_fill(sph_particles *p, int dim, double dx, double rest_density, int nblock,
                            const lahar_particle_block *blocks)
{
    int64_t total = 0;
    for (int b = 0; b < nblock; b++)
        total += sph_node_block_count(dim, dx, &blocks[b]);
    if (sph_particles_init(p, total > 0 ? total : 1) != 0)
        return -1;
    for (int b = 0; b < nblock; b++)
        if (sph_particles_add_box(p, dim, dx, rest_density, blocks[b].lo, blocks[b].hi, blocks[b].v) < 0) {
            sph_particles_free(p);
            return -1;
        }
    return p->n;
}

void lahar_sph_node_fall(sph_particles *p, const double g[3], double dt)
{
    const int64_t n = p->n;
    /* below a few thousand particles a parallel region (and its barrier, on a loaded machine)
     * costs more than the loop itself */
#pragma omp parallel for schedule(static) if (n > 8192)
    for (int64_t i = 0; i < n; i++) {
        p->vx[i] += g[0] * dt;
        p->vy[i] += g[1] * dt;
        p->vz[i] += g[2] * dt;
        p->x[i] += p->vx[i] * dt;
        p->y[i] += p->vy[i] * dt;
        p->z[i] += p->vz[i] * dt;
    }
}

double lahar_sph_node_fall_dt(const sph_particles *p, const double g[3], double dx)
{
    double vmax2 = 0.0;
    const int64_t n = p->n;
    /* max is exact whatever the order of the reduction, so this stays deterministic */
#pragma omp parallel for reduction(max : vmax2) schedule(static) if (n > 8192)
    for (int64_t i = 0; i < n; i++) {
        double v2 = p->vx[i] * p->vx[i] + p->vy[i] * p->vy[i] + p->vz[i] * p->vz[i];
        if (v2 > vmax2)
            vmax2 = v2;
    }
    double gn = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    return 0.25 * dx / (sqrt(vmax2) + sqrt(gn * dx));
}

typedef struct {
    lahar_link *link;
    lahar_node_scene ns;
    sph_particles p;
    lahar_particle_output *out;
    int nmoving;
    lahar_body_state_buf bodies; /* moving bodies at t_k (BODY_STATE(k-1)), for the coupling */
} sph_node;

static int sph_node_snapshot(sph_node *s, int64_t step, double t)
{
    lahar_particles_view v = {
        .n = s->p.n, .x = s->p.x, .y = s->p.y, .z = s->p.z, .vx = s->p.vx, .vy = s->p.vy, .vz = s->p.vz,
        .density = s->p.rho, .pressure = s->p.p, .phase = s->p.phase, .id = s->p.id,
    };
    return lahar_particle_output_snapshot(s->out, step, t, &v);
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

static int sph_node_loop(sph_node *s)
{
    char err[2048];
    lahar_link_msg msg;
    const int has_dem = s->ns.has_dem;
    const lahar_case *c = &s->ns.scene;
    for (int64_t k = 0;; k++) {
        double wait0 = lahar_link_wait_seconds(s->link);
        int rc = lahar_link_wait(s->link, LAHAR_ROLE_COORDINATOR, LAHAR_FRAME_T_MSG_STEP, k, -1, &msg);
        if (rc == LAHAR_LINK_STOP)
            return 0;
        if (rc == LAHAR_LINK_LOST) {
            fprintf(stderr, "lahar-sph: the coordinator has been silent for %.0f s (waiting for step %lld); exiting\n",
                    LAHAR_NODE_COORDINATOR_SILENCE, (long long)k);
            return 3;
        }
        if (rc != LAHAR_LINK_OK)
            return 1;
        lahar_step_t step;
        if (lahar_step_t_decode(msg.data, 0, msg.size, &step) < 0)
            return 1;
        lahar_status_t st = {0};
        err[0] = '\0';
        double c0 = lahar_now();
        /* (particle-particle work goes here: it needs no body state) */
        double compute = lahar_now() - c0;
        if (has_dem && s->nmoving > 0 && k > 0) {
            /* body states at t_k for the particle-body forces */
            rc = lahar_link_wait(s->link, LAHAR_ROLE_DEM, LAHAR_FRAME_T_MSG_BODY_STATE, k - 1, -1, &msg);
            if (rc == LAHAR_LINK_STOP)
                return 0;
            if (rc == LAHAR_LINK_LOST)
                return 3;
            if (rc != LAHAR_LINK_OK || lahar_body_state_decode(msg.data, msg.size, &s->bodies) != 0) {
                st.error = 1;
                snprintf(err, sizeof err, "undecodable BODY_STATE(%lld)", (long long)(k - 1));
            }
        }
        c0 = lahar_now();
        if (has_dem) {
            lahar_loads_t loads = {.run_id = lahar_link_run_id(s->link), .step = k};
            LAHAR_LINK_SEND(rc, s->link, LAHAR_FRAME_T_MSG_LOADS, lahar_loads_t, k, &loads);
        }
        lahar_sph_node_fall(&s->p, c->gravity, step.dt);
        if (step.write_output && sph_node_snapshot(s, k + 1, step.t_next) != 0) {
            st.error = 1;
            snprintf(err, sizeof err, "cannot write a particle snapshot in %s", s->ns.output_dir);
        }
        st.dt_proposed = lahar_sph_node_fall_dt(&s->p, c->gravity, c->sph_dx);
        st.dt_stable = st.dt_proposed;
        compute += lahar_now() - c0;
        st.compute_s = compute;
        st.wait_s = lahar_link_wait_seconds(s->link) - wait0;
        lahar_node_send_status(s->link, ROLE, k, &st, err);
        if (st.error) {
            fprintf(stderr, "lahar-sph: step %lld: %s\n", (long long)k, err);
            sph_node_wait_stop(s);
            return 1;
        }
        lahar_link_set_step(s->link, k);
    }
}

int lahar_sph_node_run(const lahar_sph_node_options *o)
{
    char err[2048];
    if (o->threads > 0)
        omp_set_num_threads(o->threads);
    lahar_transport *t = lahar_transport_open(o->lcm_url, err, sizeof err);
    if (!t) {
        fprintf(stderr, "lahar-sph: %s\n", err);
        return 2;
    }
    sph_node s;
    memset(&s, 0, sizeof s);
    unsigned want = LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_HELLO) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_SCENE) |
                    LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STEP) | LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_BODY_STATE) |
                    LAHAR_MSG_BIT(LAHAR_FRAME_T_MSG_STOP);
    s.link = lahar_link_create(t, ROLE, o->run_id, want, err, sizeof err);
    if (!s.link) {
        fprintf(stderr, "lahar-sph: %s\n", err);
        lahar_transport_close(t);
        return 2;
    }
    static const char *const caps[] = {"dim2", "dim3", "gravity"};
    int status = 0;
    int rc = lahar_node_join(s.link, ROLE, "lahar-sph/minimal", LAHAR_VERSION, caps, 3,
                             o->join_wait_s > 0 ? o->join_wait_s : 30.0, &s.ns, err, sizeof err);
    if (rc == LAHAR_LINK_STOP)
        goto done;
    if (rc != LAHAR_LINK_OK) {
        fprintf(stderr, "lahar-sph: %s\n", err);
        status = rc == LAHAR_LINK_LOST ? 3 : 2;
        goto done;
    }
    const lahar_case *c = &s.ns.scene;
    for (int i = 0; i < c->nbody; i++)
        s.nmoving += c->bodies[i].motion != LAHAR_MOTION_FIXED;
    lahar_status_t st = {0};
    err[0] = '\0';
    if (!(c->sph_dx > 0.0))
        snprintf(err, sizeof err, "the particle spacing sph.dx must be > 0 (got %g)", c->sph_dx);
    else if (lahar_sph_node_fill(&s.p, c->dim, c->sph_dx, c->sph_density, c->nblock, c->blocks) < 0)
        snprintf(err, sizeof err, "out of memory for the particles");
    else if (!(s.out = lahar_particle_output_open(s.ns.output_dir, c, c->output_fields, err, sizeof err)))
        ;
    else if (sph_node_snapshot(&s, 0, 0.0) != 0)
        snprintf(err, sizeof err, "cannot write the first particle snapshot in %s", s.ns.output_dir);
    char desc[128];
    snprintf(desc, sizeof desc, "minimal (gravity only), %lld particles", (long long)s.p.n);
    st.error = err[0] != '\0';
    st.dt_proposed = st.error ? 0.0 : lahar_sph_node_fall_dt(&s.p, c->gravity, c->sph_dx);
    st.dt_stable = st.dt_proposed;
    lahar_node_send_status(s.link, ROLE, -1, &st, st.error ? err : desc);
    if (st.error) {
        fprintf(stderr, "lahar-sph: %s\n", err);
        sph_node_wait_stop(&s);
        status = 1;
        goto done;
    }
    status = sph_node_loop(&s);
done:
    lahar_link_heartbeat_stop(s.link);
    lahar_particle_output_close(s.out);
    sph_particles_free(&s.p);
    lahar_body_state_buf_free(&s.bodies);
    lahar_case_free(&s.ns.scene);
    lahar_link_destroy(s.link);
    lahar_transport_close(t);
    return status;
}
