/* Internal data of the "spheropoly" engine, shared by the files of its general sphero-polyhedra
 * path (spheropoly*.c, the table of files in README.md) and of the sphere fast path
 * (spheropoly_spheres*.c). Not part of the engine contract (dem_engine.h). */
#ifndef LAHAR_SPHEROPOLY_IMPL_H
#define LAHAR_SPHEROPOLY_IMPL_H
#include "dem_contact.h"
#include "dem_engine.h"
#include <stdio.h>
#include "geometry.h"
#include "vec.h"

typedef struct sp_spheres sp_spheres; /* the sphere fast path (spheropoly_spheres_impl.h) */
/* Contact types: which features of body a (lower index) and b meet. */
enum { SP_VF = 0, SP_FV, SP_EE, SP_VE, SP_EV, SP_VV };

/* Bodies with more features than this get a feature grid. */
enum { SP_GRID_MIN_FEATURES = 64 };

/* Per-body loops (kick, drift) run on the thread team from this many bodies on: below it the
 * fork/join of a team costs more than the loop (README, "Performance"). */
enum { SP_PAR_MIN_BODIES = 1024 };

typedef struct {
    int a, b, type, fa, fb;
    vec3 xi;     /* tangential spring (world), kept across steps while the contact lasts */
    vec3 f;      /* force on b (a gets -f), world */
    vec3 cp;     /* contact point, world */
    vec3 n;      /* unit normal from a to b */
    double delta;
    double rstar; /* effective curvature radius (Hertz) */
} sp_contact;

typedef struct {
    int nv, ne, nf;
    int v0;      /* first vertex in vb/vw/vadj_start pools (vadj_start has nv+1 per body at va0) */
    int va0;
    int e0;      /* first edge in the edge pools */
    int f0;      /* first face in fstart (nf+1 entries at fs0) and face normal pools */
    int fs0;
    double radius, bound; /* sweep radius; bounding radius about the centre of mass */
    int grid;    /* index into e->grids or -1 */
    int material;
    lahar_motion motion;
    double mass, inertia[3];
    int isotropic; /* equal principal moments (spheres, cubes): free rotation is a plain rotation */
    int fast_sphere; /* a free sphere of the fast path (spheropoly_spheres.c): world vertex = centre */
    vec3 aabb_lo, aabb_hi; /* world box of non-free bodies (vertices +- radius) */
} sp_geo;

typedef struct {
    vec3 x, v, L, w; /* position, velocity, angular momentum and velocity (world) */
    quat q;
    vec3 fc, tc;     /* contact force / torque of the last evaluation */
} sp_state;

/* A free body in the broad-phase grid (64 bytes: one cache line). */
typedef struct {
    long long c[3]; /* cell */
    vec3 x;
    double bound;
    int id, level;
} sp_bin;

typedef struct {
    sp_contact *c;
    int n, cap;
    geom_feature_query fq;
    int *keep[2][3]; /* per side of a pair: features near the other body (vertex, edge, face) */
    vec3 *emid;      /* edge-edge prefilter: midpoints and half-lengths of the kept edges of b */
    double *ehalf;
    int oom;
} sp_thread;

struct lahar_dem_engine {
    int dim, nbody, nmat;
    vec3 g;
    double dt_stable;
    long step;                /* substeps taken since creation */
    sp_geo *geo;
    sp_state *st;
    char (*names)[LAHAR_NAME_MAX];
    dem_pair_law *laws;       /* nmat x nmat */
    /* geometry pools */
    vec3 *vb, *vw;            /* body-frame and world vertices */
    int *vadj_start, *vadj;   /* vertex neighbours (local vertex ids) */
    int (*edge)[2];           /* local vertex ids */
    int (*edge_face)[2];      /* local face ids adjacent to each edge, -1 if none */
    int *fstart;              /* per body nf+1 offsets into fv/fw (global) */
    int *fv;                  /* local vertex ids */
    vec3 *fw;                 /* world copy of the face polygons */
    vec3 *nb, *nw;            /* face normals body / world */
    geom_feature_grid *grids;
    int ngrid;
    /* broad phase */
    int nfree, *free_ids, nlarge, *large_ids;
    int nlevel;               /* grid levels: cell of level l = D 2^(l - nlevel + 1), D the largest diameter */
    double cell_inv[21];
    int level_count[21];
    int *level;               /* per free body (index into free_ids) */
    long long (*cellc)[3];
    int *bucket_of, *bucket_start, nbucket, bucket_cap, nhash, dense;
    long long dlo[3], dn[3];  /* dense grid: first cell and cells per axis */
    sp_bin *bins;             /* free bodies sorted by bucket */
    int (*pairs)[2];
    int npair, pair_cap;
    /* contacts: previous evaluation (history) and hash over it */
    sp_contact *prev, *cur;
    int nprev, contact_cap;
    int *hash, *vhash, hash_cap; /* by full key; by (pair, touching vertex); allocated size */
    int hash_n;               /* table size in use: a power of 2 >= 2 nprev (cost of a rebuild ~ contacts) */
    sp_thread *thr;
    int nthr;
    /* report accumulators over the substeps of one advance */
    vec3 *rep_f, *rep_t;
    int rep_n;
    int *ncontact_body;
    long long contacts_evaluated; /* work counter: contacts summed over every force evaluation */
    /* instability report of the last failed advance (lahar_dem_fault) */
    double max_overlap;       /* overlap limit, fraction of the smaller sweep radius (stability.max_overlap) */
    lahar_dem_fault fault;
    int has_fault;
    sp_spheres *sph;          /* sphere fast path, NULL without free spheres */
    int *other_ids, nother;   /* with sph: the bodies that are not fast spheres */
    int *move_ids, nmove, nmove_free; /* with sph: the bodies kick/drift move besides the fast
                                         spheres, the free ones first (nmove_free), then prescribed */
};

/* ---- general path: what one of its files calls in another ----------------------------------- */
/* spheropoly.c: grow *p (elements of `size` bytes) to hold `need`, doubling *cap; 0 or -1. */
int spp_grow(void **p, int *cap, int need, size_t size);
/* spheropoly.c: world vertices, face polygons and normals, and the box of a non-free body i. */
void spp_body_update_world(lahar_dem_engine *e, int i);
/* spheropoly.c: contacts and contact forces at the current positions (h: time since the last
 * evaluation), and the check that the free bodies' states are finite and not runaway; 0, or -1
 * with err (and e->fault). */
int spp_compute_forces(lahar_dem_engine *e, double h, char *err, size_t errlen);
int spp_check_finite(lahar_dem_engine *e, char *err, size_t errlen);
/* spheropoly_narrow.c: the contact history's hash over e->prev (after each evaluation and a
 * restart; 0 or -1: no memory), and the contacts of broad-phase pair (a, b), a < b, with their
 * forces into the thread buffer t (h: time since the last evaluation). */
int spp_history_rebuild(lahar_dem_engine *e);
void spp_pair_contacts(lahar_dem_engine *e, int a, int b, double h, sp_thread *t);
/* spheropoly_broad.c: the candidate pairs of the general path into e->pairs; 0 or -1: no memory. */
int spp_broad_phase(lahar_dem_engine *e);
/* spheropoly_create.c: the engine's create and destroy (lahar_dem_engine_ops). */
lahar_dem_engine *spp_create(const lahar_case *c, char *err, size_t errlen);
void spp_destroy(lahar_dem_engine *e);

/* ---- sphere fast path (spheropoly_spheres*.c) ----------------------------------------------- */
/* Set up after the bodies are built (NULL sph when there is no free sphere). 0 or -1 with err. */
int sps_create(lahar_dem_engine *e, char *err, size_t errlen);
void sps_destroy(lahar_dem_engine *e);
/* Body i is a free sphere handled by the fast path. */
int sps_is_sphere(const lahar_dem_engine *e, int i);
/* Fixed body i is a wall of the fast path (one flat face, 3D). */
int sps_is_wall(const lahar_dem_engine *e, int i);
/* Sphere-sphere and sphere-wall forces at the current positions (h: time since the last
 * evaluation). Marks the sphere-wall pairs the fast path cannot take (the sphere beyond the rim of
 * the face) for the general narrow phase. 0, or -1 with err (and e->fault on an overlap). */
int sps_forces(lahar_dem_engine *e, double h, char *err, size_t errlen);
/* Appends the marked sphere-wall pairs to e->pairs (add_pair). */
int sps_fallback_pairs(lahar_dem_engine *e, int (*add)(lahar_dem_engine *, int, int));
/* Sets the spheres' e->st[].fc/tc and e->ncontact_body to their fast-path sums (before the general
 * contacts are added); sps_accumulate_walls adds the reactions to the fast walls. */
void sps_accumulate(lahar_dem_engine *e);
void sps_accumulate_walls(lahar_dem_engine *e);
/* Instead of sps_accumulate (no general contact on a sphere): the forces stay in the fast path's
 * sums, where the kicks and sps_fc / sps_state read them. */
void sps_defer(lahar_dem_engine *e);
/* Leap-frog kick of the free spheres (velocity and angular momentum by `half` of the step), followed
 * by their drift over hdrift when hdrift > 0. */
void sps_kick(lahar_dem_engine *e, double half, const lahar_body_load *loads, double hdrift);
/* 1 when every sphere's centre, velocity and angular velocity are finite and |x| <= 1e12 m (after
 * the last kick). */
int sps_finite(const lahar_dem_engine *e);
/* The spheres' state lives in the fast path's arrays; the body states e->st of the spheres are
 * stale. sps_needs_sync: the general path meets spheres this step (other free bodies, fixed bodies
 * that are not fast walls, a sphere beyond a wall's rim); sps_sync writes their body states and
 * world vertices. sps_state: the full state of any body i (a sphere's composed from the arrays, with
 * its contact force); sps_fc its contact force and torque; sps_ncontact_of its contact count. */
int sps_needs_sync(const lahar_dem_engine *e);
void sps_sync(lahar_dem_engine *e);
sp_state sps_state(const lahar_dem_engine *e, int i);
void sps_fc(const lahar_dem_engine *e, int i, vec3 *f, vec3 *t);
int sps_ncontact_of(const lahar_dem_engine *e, int i);
int sps_ncontacts(const lahar_dem_engine *e);
int sps_nspheres(const lahar_dem_engine *e);
/* The fixed/prescribed bodies a sphere meets on the general path (not fast walls). */
int sps_general_large(const lahar_dem_engine *e, const int **ids);
int sps_write_restart(const lahar_dem_engine *e, FILE *f);
int sps_read_restart(lahar_dem_engine *e, FILE *f);

#endif
