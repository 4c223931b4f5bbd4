/* lahar-dem: the DEM node as a process. Normally started by `lahar run` inside the run's private
 * network namespace; can be started by hand for `lahar run --no-spawn` / across hosts. */
#include <stdio.h>
#include <string.h>
#include <unistd.h>
#include "dem_engine.h"
#include "output.h"
#include "dem_node.h"
#include "link.h"

int main(int argc, char **argv)
{
    lahar_link_watch_parent(); /* lahar that started this node dies: close the files, exit */
    char about[1024];
    snprintf(about, sizeof about,
             "The DEM node of lahar: joins a run announced by the coordinator (`lahar run`), builds the\n"
             "DEM engine the scene names (registered engines: %s) and advances the bodies step by step.\n"
             "  --engine NAME   use this DEM engine instead of the case's dem.engine (same protocol,\n"
             "                  same output; the lammps engine exists when lahar was built with\n"
             "                  liblammps-dev)",
             lahar_dem_engine_names());
    /* --engine NAME / --engine=NAME is the DEM node's own option: taken out before the common
     * node options are parsed */
    const char *engine = NULL;
    int n = 0;
    for (int i = 0; i < argc; i++) {
        if (i > 0 && strcmp(argv[i], "--engine") == 0) {
            if (i + 1 >= argc) {
                fprintf(stderr, "lahar-dem: --engine needs a name (registered: %s)\n", lahar_dem_engine_names());
                return 2;
            }
            engine = argv[++i];
            continue;
        }
        if (i > 0 && strncmp(argv[i], "--engine=", 9) == 0) {
            engine = argv[i] + 9;
            continue;
        }
        argv[n++] = argv[i];
    }
    argc = n;
    if (engine && !lahar_dem_engine_find(engine)) {
        fprintf(stderr, "lahar-dem: --engine '%s' is not a registered DEM engine (registered: %s)\n", engine,
                lahar_dem_engine_names());
        return 2;
    }
    lahar_dem_node_options o;
    int rc = lahar_node_parse_args(argc, argv, "lahar-dem", about,
                                   "Exit status: 0 run finished, 1 engine or output error, 2 setup error, "
                                   "3 coordinator lost.",
                                   &o);
    if (rc >= 0)
        return rc;
    o.engine = engine;
    rc = lahar_dem_node_run(&o);
    return lahar_output_exit(rc); /* HDF5's clean-up at exit would crash on a file that failed to close */
}
