/* When the coordinator calls a machine busy for a run's threads (coordinator/machine_load.c): more
 * than one thread per node, and the load average plus the threads above the cores by more than half
 * a core, or other lahar runs whose threads with this one's overfill the cores; OpenMP's default
 * (threads 0) is one thread per core. And the reading itself: the cores of
 * this process's affinity mask, a load average that is not negative. */
#define _GNU_SOURCE
#include <sched.h>
#include <stdio.h>
#include <unistd.h>
#include "machine_load.h"

#include "test_util.h"

int main(void)
{
    const struct {
        int cores;
        double load1;
        int threads, busy;
    } cases[] = {
        {2, 0.0, 2, 0},  /* an idle 2-core machine, 2 threads */
        {2, 0.4, 2, 0},  /* within the half-core slack */
        {2, 0.6, 2, 1},  /* another process holds most of a core */
        {2, 1.9, 1, 0},  /* one thread: nothing to wait for */
        {2, 0.0, 3, 1},  /* more threads than cores */
        {2, 0.0, 0, 0},  /* OpenMP's default on an idle machine: one per core */
        {2, 1.0, 0, 1},  /* ... on a busy one */
        {8, 3.0, 4, 0},  /* a big machine with room for the threads */
        {8, 3.0, 0, 1},  /* ... but not for one per core */
        {1, 5.0, 0, 0},  /* one core: one thread by default */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        lahar_machine_load m = {.cores = cases[i].cores, .load1 = cases[i].load1, .busy_now = -1.0};
        CHECK(lahar_machine_busy(&m, cases[i].threads) == cases[i].busy,
              "%d cores, load %.1f, --threads %d: busy %d, expected %d", m.cores, m.load1, cases[i].threads,
              lahar_machine_busy(&m, cases[i].threads), cases[i].busy);
    }
    /* the sample decides when it is taken: a load average left by a build that has ended ... */
    lahar_machine_load after_build = {.cores = 2, .load1 = 1.5, .busy_now = 0.05};
    CHECK(!lahar_machine_busy(&after_build, 2), "load average 1.5, 0.05 cores busy now: called busy");
    /* ... and one still running */
    lahar_machine_load still = {.cores = 2, .load1 = 1.5, .busy_now = 1.6};
    CHECK(lahar_machine_busy(&still, 2), "load average 1.5, 1.6 cores busy now: not called busy");
    /* a sample alone does not make a machine busy: the load average must say so too */
    lahar_machine_load burst = {.cores = 2, .load1 = 0.1, .busy_now = 1.6};
    CHECK(!lahar_machine_busy(&burst, 2), "a busy sample with an idle load average: called busy");
    /* another lahar run that has only just started: no load yet, busy all the same when the two
     * runs' threads (as many each) overfill the cores, even with an idle sample */
    const struct {
        int cores, other_runs, threads, busy;
    } beside[] = {
        {2, 1, 0, 1}, /* two runs of one thread per core on 2 cores */
        {2, 1, 2, 1},
        {2, 1, 1, 0}, /* one thread: nothing to wait for */
        {8, 1, 4, 0}, /* room for both */
        {8, 2, 4, 1}, /* not for three */
        {2, 0, 2, 0}, /* alone */
    };
    for (size_t i = 0; i < sizeof beside / sizeof beside[0]; i++) {
        lahar_machine_load b = {.cores = beside[i].cores, .load1 = 0.0, .busy_now = 0.0, .other_runs = beside[i].other_runs};
        CHECK(lahar_machine_busy(&b, beside[i].threads) == beside[i].busy,
              "%d cores, %d other runs, --threads %d: busy %d, expected %d", b.cores, b.other_runs, beside[i].threads,
              lahar_machine_busy(&b, beside[i].threads), beside[i].busy);
    }
    lahar_machine_load m = {0};
    cpu_set_t set;
    CHECK(lahar_machine_load_read(&m) == 0, "cannot read the machine's load");
    CHECK(sched_getaffinity(0, sizeof set, &set) == 0 && m.cores == CPU_COUNT(&set),
          "cores %d, the affinity mask has %d", m.cores, CPU_COUNT(&set));
    CHECK(m.load1 >= 0.0 && m.busy_now == -1.0, "load average %g, busy_now %g before a sample", m.load1, m.busy_now);
    CHECK(m.other_runs >= 0, "other lahar runs %d", m.other_runs); /* counted for real in coupling_busy_machine */
    CHECK(lahar_machine_sample(&m, 0.05) == 0 && m.busy_now >= 0.0 && m.busy_now <= sysconf(_SC_NPROCESSORS_CONF) + 0.5,
          "sampled %g busy cores", m.busy_now);
    CHECK(lahar_machine_threads(&m, 0) == m.cores && lahar_machine_threads(&m, 3) == 3, "threads per node");
    printf("machine: %d cores, load average %.2f, %.2f cores busy over 50 ms\n", m.cores, m.load1, m.busy_now);
    return failures ? 1 : 0;
}
