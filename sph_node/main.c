/* lahar-sph: the SPH node as a process. Normally started by `lahar run` inside the run's private
 * network namespace; can be started by hand for `lahar run --no-spawn` / across hosts. */
#include <stdio.h>
#include <unistd.h>
#include "output.h"
#include "sph_node.h"
#include "link.h"

int main(int argc, char **argv)
{
    lahar_link_watch_parent(); /* lahar that started this node dies: close the files, exit */
    lahar_sph_node_options o;
    int rc = lahar_node_parse_args(argc, argv, "lahar-sph",
                                   "The SPH node of lahar: joins a run announced by the coordinator (`lahar run`), "
                                   "fills the\nparticle blocks of the scene on a lattice and advances the particles "
                                   "step by step.",
                                   "Exit status: 0 run finished, 1 output error, 2 setup error, 3 coordinator lost.", &o);
    if (rc >= 0)
        return rc;
    rc = lahar_sph_node_run(&o);
    return lahar_output_exit(rc); /* HDF5's clean-up at exit would crash on a file that failed to close */
}
