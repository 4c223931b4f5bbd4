/* bench_dem --lammps-data: the settled pile of a LAMMPS data file (atom_style sphere) as a lahar
 * scene, timed against LAMMPS itself (through its C library, when built with it) in the same run. */
#ifndef LAHAR_BENCH_LAMMPS_H
#define LAHAR_BENCH_LAMMPS_H

typedef struct {
    const char *file;  /* LAMMPS data file written by /work/shared/bench/dem/in.settle3d */
    int warm, steps;   /* untimed warm-up steps (rebuild the tangential history), timed steps */
    int threads;       /* OpenMP threads of the lahar engine */
    int lammps;        /* 1: also run LAMMPS on the same file (needs LAHAR_HAVE_LAMMPS) */
    double ke_tol;     /* > 0: exit 1 unless lahar's KE after warm-up + steps is within this
                          factor of LAMMPS's (|ln(ke/ke_lmp)| <= ln(ke_tol)) */
    double contact_tol;/* > 0: exit 1 unless the sphere-sphere contact counts agree within this
                          relative tolerance */
} bench_lammps_opts;

/* Prints a table; returns 0, 1 when a tolerance check failed, 2 on a bad file or engine failure. */
int bench_lammps_run(const bench_lammps_opts *o);

#endif
