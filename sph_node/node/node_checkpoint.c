/* The node's part of a checkpoint (common/io/checkpoint.h): everything step k + 1 reads of the
 * state after step k, in the particles' current (sorted) order: the particle arrays (incl. the
 * rates of the last evaluation, which the first kick of the next step uses, and the soil's stress
 * and stress rate), the solver's counters (step: the Shepard filter's period), the transport
 * velocity's b, the coupling's forces and contact points of the last evaluation (LOADS of the next
 * step) and the soil-DEM friction springs, the body states the coupling uses, the probes' sampling
 * slots and this node's own counters. Buffers that every evaluation refills before reading (cells,
 * EOS terms, SPS stress, soil pass scratch) are not stored. One function both ways: 0, or -1 with
 * the message in f->err. */
#include <stdio.h>
#include <string.h>
#include "checkpoint.h"
#include "sph_node_run.h"

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

int sph_node_state_io(sph_node *s, lahar_ckpt_file *f, int64_t *k, double *t_now)
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
int sph_node_checkpoint(sph_node *s, int64_t state_step, double t, char *err, size_t errlen)
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
