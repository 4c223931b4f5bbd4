/* The SPH node's state, shared by the files of sph_node/node/ (and only by them), and the steps one
 * file calls in another. The node's public entry points are in sph_node.h. */
#ifndef LAHAR_SPH_NODE_RUN_H
#define LAHAR_SPH_NODE_RUN_H
#include <stdint.h>
#include "case.h"
#include "checkpoint.h"
#include "instability.h"
#include "lahar_status_t.h"
#include "lahar_step_t.h"
#include "link.h"
#include "output.h"
#include "scene_msg.h"
#include "sph_fluid.h"
#include "sph_inflow.h"
#include "sph_node.h"
#include "sph_probes.h"

#define ROLE LAHAR_ROLE_SPH

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

/* node_fill.c: the particles of the case's blocks (lahar_sph_node_fill, sph_node.h) */
int sph_node_add_blocks(sph_particles *p, const lahar_case *c, char *err, size_t errlen);
int64_t sph_node_count(const lahar_case *c);

/* node_output.c: snapshots, the final snapshot of a stopped run, the probes */
int sph_node_snapshot(sph_node *s, int64_t step, double t);
void sph_node_mark_last(const sph_node *s, const char *name, const char *text);
void sph_node_final_snapshot(sph_node *s, const lahar_link_msg *stop, int64_t k, double t);
void sph_node_stopped_half_step(sph_node *s, const lahar_link_msg *stop, int64_t k, const lahar_step_t *step);
int sph_node_probes_open(sph_node *s, char *err, size_t errlen);
int sph_node_probes_sample(sph_node *s, int64_t k, double t);

/* node_fixed_bodies.c: a scene of fixed bodies only (no DEM node): their files, from this node */
int sph_node_fixed_snapshot(sph_node *s, int64_t step, double t);
int sph_node_fixed_open(sph_node *s, char *err, size_t errlen);
int sph_node_fixed_forces(sph_node *s, int64_t k, const lahar_step_t *step, char *err, size_t errlen);

/* node_checks.c: particles that crossed a body surface, and the stability checks */
int64_t sph_node_check_particles(const sph_node *s, int64_t k, double t, lahar_instability *u);
void sph_node_crossing_message(const sph_node *s, int64_t k, double t, char *err, size_t n);
void sph_node_crossing_report(const sph_node *s, int64_t k, double t, lahar_instability *u);

/* node_checkpoint.c: the node's part of a checkpoint, both ways */
int sph_node_checkpoint(sph_node *s, int64_t state_step, double t, char *err, size_t errlen);
int sph_node_state_io(sph_node *s, lahar_ckpt_file *f, int64_t *k, double *t_now);

/* node_loop.c: the loads to the DEM node */
int sph_node_build_loads(sph_node *s, int64_t *npoints);

#endif
