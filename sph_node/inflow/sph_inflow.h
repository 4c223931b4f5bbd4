/* Open boundaries of the SPH fluid: inlets with buffer zones, outlets, the domain box
 * (definitions: common/scene/inflow.h; case sections inlets:, outlets:, domain:).
 *
 * Inlet (buffer zone, after Federico, Marrone, Colagrossi, Aristodemo & Antuono 2012, "Simulating
 * 2D open-channel flows through an SPH model", Eur. J. Mech. B/Fluids 34:35-46, section 3, and
 * the DualSPHysics inlet/outlet of Tafuni, Domínguez, Vacondio & Crespo 2018, Comput. Methods
 * Appl. Mech. Eng. 342:604-624): behind the inlet section lie `layers` rows of buffer particles on
 * the section's own lattice (spacing dx along its edges and its normal), only the slots whose
 * centre lies below the prescribed level. Buffer particles take part in the particle sums as water
 * neighbours (the fluid near the inlet has a full kernel support), but their state is prescribed:
 * before every step (sph_inflow_apply) each gets v = u(t) n, the hydrostatic density of its
 * depth below the level (p = rho0 |g| (h - s), the EOS inverted: no pressure jump at the section
 * beyond the hydrostatic one) and zero rates, so the step's drift moves it by exactly u(t_k) dt_k
 * along n. The inlet keeps the displacement D = sum u(t_k) dt_k; row r (r = 0, 1, ...) sits at
 * the normal coordinate D - (r + 1/2) dx: it is created when that reaches -layers dx (behind the
 * buffer) and its particles become fluid particles when it reaches 0 (they cross the section),
 * keeping their position, velocity, density, mass and rates. With a level table h(t) a row takes
 * the slots below h at the time it will cross the section (t - c/u at creation, c its normal
 * coordinate: the buffer's transit does not delay the level) and the buffer's density follows h(t). A created particle gets the next
 * unique id (never reused) and the mass rho dx^D of its hydrostatic density rho (as the blocks'
 * particles: its volume is its lattice cell). Discharge: the particles entering up to time t
 * carry the volume A dx floor(D/dx + 1/2), A = (slots) dx^(D-1), i.e. A D = the integral of
 * u A dt within one row (A dx).
 *
 * Outflow: before every step a domain particle beyond an outlet (along its outward normal, within
 * its extent and depth) or outside the domain box is removed (the others keep their order) and
 * counted with its mass, per phase. Buffer particles are never removed.
 *
 * Counts and storage: the particle arrays are sized at setup for the initial particles plus every
 * inlet's max_particles (sph_inflow_capacity); an inlet that would exceed it stops the run with a
 * message naming the key to raise. Nothing is allocated per step. Mass balance: the mass of the
 * domain particles changes by exactly (entered - removed) up to the round-off of the sums. */
#ifndef LAHAR_SPH_INFLOW_H
#define LAHAR_SPH_INFLOW_H
#include <stdint.h>
#include "inflow.h"
#include "sph_fluid.h"

typedef struct {
    const lahar_inlet *def;
    double t1[3], t2[3];   /* unit edge directions (2D: t2 = 0) */
    double up[3];          /* unit vector against gravity */
    double s_low;          /* height (along up) of the section's lowest point */
    int nslot;             /* lattice slots of the section below the (largest) level */
    double *slot;          /* nslot x 3: slot centres on the section */
    double *slot_s;        /* nslot: their heights above s_low */
    double area;           /* slots below the current level x dx^(D-1): m in 2D (per unit
                              thickness), m^2 in 3D */
    double h;              /* the current level (lahar_inlet_level) */
    double disp;           /* D = sum of u dt so far */
    int64_t next_row;      /* rows created so far */
    int64_t created;       /* particles created (buffer particles included) */
    int64_t max_particles; /* limit of created (the case's inlets[k].max_particles or the estimate) */
    int layers;            /* buffer rows (the case's, or ceil(kernel support / dx)) */
    double u;              /* velocity of the current step, m/s */
} sph_inlet;

/* Cumulative counters since the start of the run (checkpointed). */
typedef struct {
    int64_t entered;        /* particles that crossed an inlet section into the domain */
    double entered_mass;
    int64_t removed[2];     /* per phase (0 water, 1 soil): particles removed by outlets / domain */
    double removed_mass[2];
    int64_t created;        /* particles created in buffers (ids handed out) */
} sph_flow_counts;

typedef struct {
    int dim;
    double dx;
    double gravity[3];
    int ninlet;
    sph_inlet *in;
    int noutlet;
    const lahar_outlet *out;
    int has_domain;
    double lo[3], hi[3];
    int64_t next_id;        /* the id the next created particle gets */
    sph_flow_counts counts;
    unsigned char *drop;    /* per particle (cap): marks of the removal pass */
} sph_inflow;

/* Set up the open boundaries (definitions borrowed: they must outlive fl). support: the kernel's
 * support radius (the default buffer depth). t_end: the end of the
 * run (for the default max_particles). Returns 0, or -1 with a message in err (an inlet without
 * gravity, a level below one slot, a section shorter than dx). Allocates nothing per particle. */
int sph_inflow_init(sph_inflow *fl, int dim, double dx, double support, const double gravity[3], int ninlet, const lahar_inlet *inlets,
                    int noutlet, const lahar_outlet *outlets, int has_domain, const double lo[3], const double hi[3],
                    double t_end, char *err, int errlen);
/* Particles the open boundaries may add to the initial ones (the sum of the inlets' limits). */
int64_t sph_inflow_capacity(const sph_inflow *fl);
/* After the initial particles are in f->p (capacity >= their count + sph_inflow_capacity): the
 * marks, the removal scratch and the first `layers` rows of every inlet at the state of t.
 * Returns 0, or -1 with a message in err. */
int sph_inflow_start(sph_inflow *fl, sph_fluid *f, double t, char *err, int errlen);
/* Before the step from t to t + dt: removal (outlets, domain), buffer particles that crossed their
 * section become fluid, new rows, buffer state set to the hydrograph at t, D += u(t) dt.
 * Returns the number of particles added minus removed (>= INT64_MIN / 2), or INT64_MIN with a
 * message in err (capacity exhausted). */
int64_t sph_inflow_apply(sph_inflow *fl, sph_fluid *f, double t, double dt, char *err, int errlen);
/* The inlet's velocity at t (the hydrograph; a discharge divided by the area below h(t)). */
double sph_inflow_velocity(const sph_inflow *fl, int k, double t);
/* The wetted area of inlet k's lattice below the level h: slots x dx^(D-1). */
double sph_inflow_area(const sph_inflow *fl, int k, double h);
/* Mass of the domain particles (buffer particles excluded), summed in particle order. */
double sph_inflow_domain_mass(const sph_inflow *fl, const sph_particles *p);
void sph_inflow_free(sph_inflow *fl);

/* The SPH node's side (sph_inflow_node.c). */
#include "checkpoint.h"
#include "scene.h"
/* 1 when the case has inlets, outlets or a domain box. */
int sph_inflow_case_wanted(const lahar_case *c);
/* sph_inflow_init from the case (the kernel support of prm, the case's gravity and t_end). */
int sph_inflow_setup_case(sph_inflow *fl, const lahar_case *c, const sph_params *prm, char *err, int errlen);
/* The counters of a snapshot / summary (LAHAR_FLOW_NVAL values, names in common/io/output.h). */
void sph_inflow_values(const sph_inflow *fl, const sph_particles *p, double *v);
/* Store / load the open boundaries' state: the inlet marks of the p->n particles (p->n already
 * set), the next id, the counters, each inlet's displacement, velocity, rows and particles
 * created. 0 or -1 (message in f->err). */
int sph_inflow_state_io(sph_inflow *fl, sph_particles *p, lahar_ckpt_file *f);

#endif
