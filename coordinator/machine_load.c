/* How busy the machine is when a run starts (machine_load.h). */
#define _GNU_SOURCE
#include "machine_load.h"
#include <sched.h>
#include <stdlib.h>

int lahar_machine_load_read(lahar_machine_load *m)
{
    cpu_set_t set;
    double load[1];
    if (sched_getaffinity(0, sizeof set, &set) != 0 || getloadavg(load, 1) != 1)
        return -1;
    m->cores = CPU_COUNT(&set);
    m->load1 = load[0];
    return m->cores > 0 ? 0 : -1;
}

int lahar_machine_threads(const lahar_machine_load *m, int threads)
{
    return threads > 0 ? threads : m->cores;
}

int lahar_machine_busy(const lahar_machine_load *m, int threads)
{
    const int t = lahar_machine_threads(m, threads);
    /* half a core of slack: the load average also counts short-lived tasks and decays over a
     * minute, so a run started just after another one reads some of that one's load */
    return t > 1 && m->load1 + t > m->cores + 0.5;
}
