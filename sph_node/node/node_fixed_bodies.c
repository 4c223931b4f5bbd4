/* A scene whose bodies are all fixed. Bodies that never move need no integration: the coordinator
 * then starts no DEM node (no STEP, STATUS, LOADS or BODY_STATE for it), the coupling uses the
 * scene's poses (it always does for fixed bodies) and this node writes the body files the DEM node
 * would have written, from the same numbers: bodies.h5 (the scene's poses, quaternions normalised
 * as the engine stores them, zero velocities), forces.h5 (per step k the row of t_{k+1} holding
 * the fluid's force at t_k: the resultants LOADS(k) would carry; fixed bodies have no body-body
 * contacts) and contacts.h5 (the points of the marked bodies, at the steps that start at an output
 * time). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "shape_build.h"
#include "vec.h"
#include "sph_node_run.h"

int sph_node_fixed_snapshot(sph_node *s, int64_t step, double t)
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
int sph_node_fixed_open(sph_node *s, char *err, size_t errlen)
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
int sph_node_fixed_forces(sph_node *s, int64_t k, const lahar_step_t *step, char *err, size_t errlen)
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
