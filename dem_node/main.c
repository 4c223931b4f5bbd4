/* lahar-dem: the DEM node as a process. Normally started by `lahar run` inside the run's private
 * network namespace; can be started by hand for `lahar run --no-spawn` / across hosts. */
#include <stdio.h>
#include <unistd.h>
#include "dem_engine.h"
#include "output.h"
#include "dem_node.h"

int main(int argc, char **argv)
{
    char about[512];
    snprintf(about, sizeof about,
             "The DEM node of lahar: joins a run announced by the coordinator (`lahar run`), builds the\n"
             "DEM engine the scene names (registered engines: %s) and advances the bodies step by step.",
             lahar_dem_engine_names());
    lahar_dem_node_options o;
    int rc = lahar_node_parse_args(argc, argv, "lahar-dem", about,
                                   "Exit status: 0 run finished, 1 engine or output error, 2 setup error, "
                                   "3 coordinator lost.",
                                   &o);
    if (rc >= 0)
        return rc;
    rc = lahar_dem_node_run(&o);
    return lahar_output_exit(rc); /* HDF5's clean-up at exit would crash on a file that failed to close */
}
