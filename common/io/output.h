/* Run output in HDF5 with XDMF sidecars for ParaView (layout documented in tools/README.md).
 *
 *   OUT/bodies.h5   /header (units, version, case, per-body names, materials, motion, mass,
 *                   inertia), /geometry (display meshes written once), /snapshots/NNNNNN
 *                   (time, step, per-body pose and velocities, world-frame display vertices of
 *                   the moving bodies). Closed after every snapshot, and written so that the
 *                   file on disk is always complete, even when its writer is killed (see
 *                   lahar_output_remove_twins), and other programs can open it while a job runs.
 *   OUT/bodies.xmf  XDMF temporal collection, rewritten in place after each snapshot.
 *   OUT/forces.h5   per-body force stream (SWMR: readable while the run appends to it).
 *   OUT/particles.h5 + OUT/particles.xmf   SPH particles (SoA datasets, fields selectable).
 *   OUT/lahar.xmf   bodies and particles in one XDMF (lahar_output_xdmf_combine).
 *   OUT/contacts.h5 fluid contact points and their forces on the bodies marked record_contacts.
 *   OUT/gauges.h5   pressure probes and level gauges of the case (probes:), SWMR like forces.h5. */
#ifndef LAHAR_OUTPUT_H
#define LAHAR_OUTPUT_H
#include <stddef.h>
#include <stdint.h>
#include "scene.h"

typedef struct lahar_body_output lahar_body_output;

/* Create OUT/bodies.h5 (header + geometry), OUT/bodies.xmf and, when c->output_forces is set,
 * OUT/forces.h5 for the bodies of case c (outdir must exist). Returns NULL and a message in err on failure. */
lahar_body_output *lahar_body_output_open(const char *outdir, const lahar_case *c, char *err, size_t n);
/* Append snapshot (s has c->nbody entries) as /snapshots/NNNNNN and add it to bodies.xmf.
 * Returns 0, or -1 on an HDF5/file error (message on stderr). */
int lahar_body_output_snapshot(lahar_body_output *o, int64_t step, double t, const lahar_body_state *s);
/* Offer one row of the force stream (r has c->nbody entries). Call it every step: rows are kept
 * every step when c->forces_interval is 0, otherwise the first row at or after every multiple
 * of forces_interval. Rows are buffered and flushed at least every 0.5 s of wall time and when
 * the buffer is full. Returns 0, or -1 on error. */
int lahar_body_output_forces(lahar_body_output *o, int64_t step, double t, const lahar_body_report *r);
/* Flush and close everything (NULL is fine). Also refreshes OUT/lahar.xmf. */
void lahar_body_output_close(lahar_body_output *o);

/* Particle fields a writer stores besides the position (always stored). */
enum {
    LAHAR_PFIELD_VELOCITY = 1 << 0, /* vx, vy, vz */
    LAHAR_PFIELD_DENSITY = 1 << 1,
    LAHAR_PFIELD_PRESSURE = 1 << 2,
    LAHAR_PFIELD_PHASE = 1 << 3,    /* int32 */
    LAHAR_PFIELD_ID = 1 << 4,       /* int64 */
    LAHAR_PFIELD_STRESS = 1 << 5,   /* soil effective stress, n x 6: xx, xy, xz, yy, yz, zz (Pa, tension
                                       positive; 0 for water particles) */
    LAHAR_PFIELD_ALL = 0x1f         /* every field of a water-only scene; soil scenes add STRESS */
};

/* One snapshot of particles as structure-of-arrays. Arrays for fields not selected at open may
 * be NULL; z may be NULL in 2D (written as zeros). */
typedef struct {
    int64_t n;
    const double *x, *y, *z;
    const double *vx, *vy, *vz;
    const double *density, *pressure;
    const int32_t *phase;
    const int64_t *id;
    const double *stress[6]; /* SoA xx, xy, xz, yy, yz, zz; NULL without soil (then not written) */
    /* open boundaries only (NULL without inlets, outlets or domain; sph_node/sph_inflow.h):
     * inlet: per particle, the inlet whose buffer holds it, -1 in the domain (dataset `inlet`);
     * flow: LAHAR_FLOW_NVAL cumulative counters since the start of the run, written as the
     * snapshot's attributes named in lahar_flow_names */
    const int32_t *inlet;
    const double *flow;
} lahar_particles_view;

#define LAHAR_FLOW_NVAL 8
/* entered (particles that crossed an inlet into the domain) and their mass, removed water and
 * soil particles (outlets, domain box) and their masses, particles created in buffers, the mass
 * of the domain's particles at the snapshot (buffers excluded); kg/m in 2D */
extern const char *const lahar_flow_names[LAHAR_FLOW_NVAL];

typedef struct lahar_particle_output lahar_particle_output;

/* Create OUT/particles.h5 and OUT/particles.xmf; `fields` is a mask of LAHAR_PFIELD_* (pass
 * c->output_fields, which the case loader fills from output: fields). */
lahar_particle_output *lahar_particle_output_open(const char *outdir, const lahar_case *c, unsigned fields,
                                                  char *err, size_t n);
int lahar_particle_output_snapshot(lahar_particle_output *o, int64_t step, double t, const lahar_particles_view *p);
void lahar_particle_output_close(lahar_particle_output *o);

/* Per-contact-point forces of the bodies a case marks record_contacts (OUT/contacts.h5, layout in
 * tools/README.md): the points where the fluid pushes on them and the forces there, per snapshot.
 * open returns NULL with err empty when no body is marked (nothing to write), NULL with a message
 * on failure. */
typedef struct lahar_contact_output lahar_contact_output;
lahar_contact_output *lahar_contact_output_open(const char *outdir, const lahar_case *c, char *err, size_t n);
/* One snapshot at (step, t) from loads in the layout of loads_t: nlisted bodies body_id[i] with
 * npoints[i] points each, consecutive in x (positions) and f (forces on the body), and their
 * resultants force[i], torque[i]. Marked bodies not listed get an empty group. o NULL: no-op.
 * Reopens and closes the file, so it is complete on disk after every call. 0 or -1. */
int lahar_contact_output_write(lahar_contact_output *o, int64_t step, double t, int nlisted, const int32_t *body_id,
                               const int32_t *npoints, const double (*x)[3], const double (*f)[3],
                               const double (*force)[3], const double (*torque)[3]);
void lahar_contact_output_close(lahar_contact_output *o);

/* Probes of the case (probes:, OUT/gauges.h5, SWMR like forces.h5: readable while the run
 * appends): per probe /probes/NAME/{t, step, p} (pressure, Pa) or {t, step, h} (level gauges, m)
 * with units attributes and the probe's kind, position, body, normal, size, rate, method (and for
 * level gauges floor and top) as attributes of its group. open returns NULL
 * with err empty when the case has no probes (nothing is written), NULL with a message on
 * failure. write appends (step, t, p[k]) to every probe k with due[k] set (buffered; flushed
 * every 1024 rows or 0.5 s of wall time and at close). o NULL: no-op. */
typedef struct lahar_gauge_output lahar_gauge_output;
lahar_gauge_output *lahar_gauge_output_open(const char *outdir, const lahar_case *c, char *err, size_t n);
int lahar_gauge_output_write(lahar_gauge_output *o, int64_t step, double t, const double *p, const int *due);
void lahar_gauge_output_close(lahar_gauge_output *o);

/* Checkpoints (common/io/checkpoint.h): a writer hands its buffered stream rows to the file before
 * its node writes a checkpoint, so that rows up to the checkpoint survive a kill. 0 or -1. */
int lahar_body_output_sync(lahar_body_output *o);
int lahar_gauge_output_sync(lahar_gauge_output *o);
/* `lahar resume` before the nodes start: cut the output of OUT back to the checkpoint of `step`
 * (the state after step - 1): snapshots of particles.h5 and bodies.h5 with a larger step (and
 * the one at `step` itself unless snapshot_at_step, i.e. unless it was a scheduled output time,
 * not the final snapshot of a stopped run), contacts.h5 entries from `step` on, rows of
 * forces.h5 and gauges.h5 after `step`; marks of a stopped run are removed. The writers, opened
 * with lahar_case.resume set, then continue these files. 0, or -1 with a message. */
int lahar_output_resume_trim(const char *outdir, int64_t step, int snapshot_at_step, char *err, size_t n);

/* The snapshot files bodies.h5, particles.h5 and contacts.h5 each have a twin while their writer
 * runs, OUT/.<name>.twin: every snapshot goes into the twin first, which then takes the file's
 * name, so that a writer killed at any moment leaves the file complete with every snapshot it
 * finished. A writer removes its twin when it closes; once the writers of OUT are gone (a node
 * killed), this removes what they left. */
void lahar_output_remove_twins(const char *outdir);

/* Write OUT/lahar.xmf: one temporal collection whose time steps hold the body grids and the
 * particle grid of the snapshots found in OUT/bodies.h5 and OUT/particles.h5 (either may be
 * missing). Safe to call when no writer has the files open, e.g. by the coordinator at the end
 * of a run; the writers also call it from their close. Returns 0, or -1 with a message. */
int lahar_output_xdmf_combine(const char *outdir, char *err, size_t n);

/* A run stopped by an instability or an error: mark the last snapshot of OUT/<file> (bodies.h5,
 * particles.h5) with a string attribute `name` holding `text` (the report), so that whoever opens
 * the final snapshot sees why the run ended there. 0, or -1 (message on stderr). */
int lahar_output_mark_last_snapshot(const char *outdir, const char *file, const char *name, const char *text);
/* The last snapshot of OUT/<file>: its group ("/snapshots/NNNNNN"), step and time. 0, or -1 when
 * the file is missing or has none. */
int lahar_output_last_snapshot(const char *outdir, const char *file, char *group, size_t n, int64_t *step, double *t);

/* Room on the disk. Every writer above first checks that the file system of OUT has room for
 * what it is about to write, with a margin of LAHAR_OUTPUT_RESERVE for the other node writing at
 * the same time, and refuses (-1, nothing written, the file as it was) otherwise: HDF5 that runs
 * out of space in the middle of a write can leave a file that no longer opens. */
#define LAHAR_OUTPUT_RESERVE (256.0 * 1024.0)
/* The last failure of a writer in this thread: which file, what, at which step and time, and
 * why ("no space left on device", with the bytes free); "" when none. */
const char *lahar_output_error(void);
/* Replace the message in err (a caller's generic "cannot write ...") by lahar_output_error()
 * when there is one. */
void lahar_output_explain(char *err, size_t n);
/* 1 when an HDF5 file failed to close in this process: HDF5's clean-up at exit crashes on what
 * it left (HDF5 1.10), so the program leaves with _exit after flushing its own streams. */
int lahar_output_failed(void);
/* The end of main() in a program that writes HDF5: returns status, or leaves with _exit(status)
 * after flushing stdio when lahar_output_failed(). */
int lahar_output_exit(int status);
/* Bytes an unprivileged writer may still use on the file system of directory dir (-1 unknown). */
double lahar_output_free_bytes(const char *dir);

/* The files a run writes into OUT (NULL-terminated): HDF5 streams, XDMF sidecars, the
 * coordinator's summary.json and `lahar check`'s check.json / check.png. A new output file is
 * added here, so that `lahar run --overwrite` removes it with the rest of an earlier run. */
extern const char *const lahar_output_run_files[];

/* A file whose SWMR writer died (forces.h5 after a node was killed) keeps the "open for writing"
 * flags in its superblock, and h5dump / h5py refuse it. Clears them when they are set, as h5clear
 * -s does (HDF5's file-access property "clear_status_flags"), so every row the writer flushed can
 * be read. Only for a file no process writes any more. 0 nothing to do (or no such file), 1
 * cleared, -1 the file cannot be opened even so. */
int lahar_output_release_swmr(const char *path);

/* Display mesh of a sphero-polyhedron for viewers (not used by the physics): a closed surface of
 * triangles in 3D (spheres: icospheres; polyhedra: core faces offset by the sweep radius plus
 * flat bevels along edges and fans at corners; rods: spheres + tubes), line segments in the
 * x-y plane in 2D (convex bodies: the rounded outline; segments/polylines: thin quads).
 * Coordinates in the shape's own frame; `convex` is the body's flag (2D outline choice). Built
 * once at setup. */
typedef struct {
    int nvert;
    double (*v)[3];
    int ncell;
    int nodes_per_cell; /* 3 (triangles, 3D) or 2 (line segments, 2D) */
    int32_t *cell;      /* ncell * nodes_per_cell vertex indices */
} lahar_display_mesh;

/* H5Fcreate (create = 1) / H5Fopen with HDF5's automatic error printing off: callers print one
 * message of their own. fapl is an hid_t (int64_t here to keep hdf5.h out of this header). */
int64_t lahar_h5_file_open(const char *path, unsigned flags, int64_t fapl, int create);

int lahar_display_mesh_build(const lahar_shape *s, int dim, int convex, lahar_display_mesh *m);
void lahar_display_mesh_free(lahar_display_mesh *m);

#endif
