/* How busy the machine is when a run starts, against the OpenMP threads the run asks for. */
#ifndef LAHAR_MACHINE_LOAD_H
#define LAHAR_MACHINE_LOAD_H

typedef struct {
    int cores;       /* CPUs this process may run on (its affinity mask) */
    double load1;    /* load average of the last minute: tasks running or waiting for a CPU (or disk) */
    double busy_now; /* cores busy over a short sample (lahar_machine_sample), or -1: not sampled */
    int other_runs;  /* other `lahar run|check|resume` processes on the machine (/proc) */
} lahar_machine_load;

/* Read cores, load1 and other_runs (busy_now = -1). Returns 0, or -1 when cores or load1 cannot be
 * read. */
int lahar_machine_load_read(lahar_machine_load *m);

/* Sample busy_now from /proc/stat over `seconds` (this process sleeping meanwhile). Returns 0, or -1
 * (busy_now stays -1). */
int lahar_machine_sample(lahar_machine_load *m, double seconds);

/* The threads a node runs: --threads N, or OpenMP's default of one per core (threads = 0). */
int lahar_machine_threads(const lahar_machine_load *m, int threads);

/* 1 when a node's threads (more than one) would share their cores with other work: the load
 * average plus the threads exceed the cores by more than half a core, and so do the cores busy now
 * (when sampled); or other lahar runs are on the machine and, each with as many threads, all of
 * them exceed the cores by more than half a core (a run started beside another one that has only
 * just started sees no load yet). Such threads wait for each other at every parallel loop of a
 * step while the other work holds a core. */
int lahar_machine_busy(const lahar_machine_load *m, int threads);

#endif
