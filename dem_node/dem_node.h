/* The DEM node's process loop: joins a run, builds the engine named by the scene through the
 * engine table (dem_engine.h), and answers each STEP of the coordinator (protocol in
 * lcm_types/README.md). Used by lahar-dem (dem_node/main.c) and by `lahar run --in-process`. */
#ifndef LAHAR_DEM_NODE_H
#define LAHAR_DEM_NODE_H
#include <stdint.h>

#include "node_cli.h"

/* The node's options: the command line every node takes (common/protocol/node_cli.h). */
typedef lahar_node_options lahar_dem_node_options;

/* Runs until the coordinator stops the run. Returns the process exit status: 0 normal stop,
 * 1 engine/output error, 3 coordinator lost, 2 setup error. */
int lahar_dem_node_run(const lahar_dem_node_options *o);

#endif
