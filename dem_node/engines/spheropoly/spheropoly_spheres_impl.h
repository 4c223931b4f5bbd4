/* The sphere fast path's internal data, shared by its files (spheropoly_spheres*.c, the table of
 * files in README.md). The rest of the engine reaches the fast path only through the sps_
 * functions of spheropoly_impl.h. */
#ifndef LAHAR_SPHEROPOLY_SPHERES_IMPL_H
#define LAHAR_SPHEROPOLY_SPHERES_IMPL_H
#include "spheropoly_impl.h"


/* Parallel loops from this many spheres on: below, a team's fork/join per loop costs more than the
 * loop (512 spheres on 2 threads took twice the CPU time of 1 thread; 10,000 gained, dem_speed.md). */
enum { SPS_PAR_MIN = 2048 };

typedef struct {
    int n, cap;
    int *a, *b;           /* sphere a, and sphere b > a (sphere list) or wall index (wall list) */
    vec3 *xi;             /* tangential spring */
    unsigned char *touch; /* in contact at the last evaluation (xi is its spring, else 0) */
    unsigned char *fall;  /* wall list: the centre is beyond the face's rim, general path */
    unsigned char *deep;  /* wall list: the centre was farther than the skin inside the face's rim at the build */
    vec3 *f, *ta, *tb;    /* force on b (wall list: on the sphere), torque on a and on b; sphere list:
                             only the entries across two parts of the threaded loop */
    double *delta;        /* wall list: overlap */
    int *ci;              /* sphere list: scratch of the force loop (the entries in contact) */
    dem_pair_consts *pc;  /* normal-law constants of the pair (m*, R* fixed) */
} sps_list;

typedef struct {
    int n, cap;
    int *a, *b;
    vec3 *xi;
} sps_hist; /* the touching entries of a list, sorted: carried over a rebuild or a restart */

struct sp_spheres {
    int n;                /* free spheres */
    int *body;            /* body of sphere k, ascending */
    int *of_body;         /* per body: sphere index, or -1 */
    int *wall_of_body;    /* per body: wall index, or -1 */
    int nwall, *wall_body;
    int ngen, *gen_large; /* fixed/prescribed bodies that are not fast walls (general path) */
    double *rad, *mass;
    int *mat;             /* material */
    double *iner;         /* moment of inertia (3D: the equal moments; 2D: about z) */
    double *inv_iner;     /* 1 / iner */
    int *v0;              /* index of the sphere's vertex in e->vw */
    /* the spheres' state (SoA by field, contiguous by sphere): the body states in e->st are stale
     * (sps_sync writes them, sps_state reads the state) */
    vec3 *x, *v, *w, *L;
    double *qw, *qx, *qy, *qz; /* orientation, unit quaternion by component */
    int nfall;            /* wall entries of the last evaluation beyond the face's rim (general path) */
    int finite;           /* every centre, velocity and angular velocity finite, |x| <= 1e12 m */
    double worst;         /* largest squared displacement of a centre since the list build */
    double skin, rmax;
    vec3 *x0;             /* centres at the last build */
    int built;
    sps_list pl, wl;      /* sphere-sphere and sphere-wall lists */
    sps_hist ph, wh;      /* history hand-over */
    int *bcount;          /* n + 1 counters of the list build */
    int *wstart;          /* per sphere its wall entries [wstart[k], wstart[k+1]) */
    int *pstart;          /* per sphere a its sphere-sphere entries as a: [pstart[a], pstart[a+1]) */
    vec3 *wunit;          /* per wall its unit normal (the one geom_point_polygon_inside uses) */
    vec3 *wnrm, *wp0;     /* per wall its face normal and first vertex (world) */
    double *wrad;         /* per wall its sweep radius */
    /* the force loop in parts of consecutive spheres [part[t], part[t+1]) of about equal work, one
     * per thread; xpair[xstart[t] .. xstart[t+1]) are the entries of part t whose partner is in a
     * later part (npart = 1: no thread team, no such entry); xin[xinstart[t] .. xinstart[t+1]) the
     * entries whose partner b is in part t from earlier parts, by (b, a) */
    int npart, *part, *xstart, *xpair, *xinstart, *xin, xcap;
    vec3 *sf, *st;        /* per sphere: fast-path force and torque */
    int *scnt;
    /* build grid */
    int *cell_start, *cell_of, *order, ncell_cap;
    int *cand, cand_cap;
    int ncontact;
    int deferred;         /* the spheres' forces are in sf/st/scnt only (no general contact on a
                             sphere), not in the body states */
};

/* spheropoly_spheres.c: grow list l to hold `need` entries (0 or -1: no memory); the touching
 * entries of list l (sorted) into h (0 or -1); the springs of h handed to the equal (a, b) entries
 * of the new list l (both sorted). */
int sps_list_reserve(sps_list *l, int need);
int sps_hist_take(sps_hist *h, const sps_list *l);
void sps_hist_give(const sps_hist *h, sps_list *l);
/* spheropoly_spheres_list.c: the Verlet lists of the spheres at their current centres; 0 or -1:
 * no memory. */
int sps_build_lists(lahar_dem_engine *e);

#endif
