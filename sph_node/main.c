/* lahar-sph: the SPH node as a process. Normally started by `lahar run` inside the run's private
 * network namespace; can be started by hand for `lahar run --no-spawn` / across hosts. */
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include "sph_node.h"
#include "netns.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lahar-sph [--lcm-url URL] [--run-id ID] [--threads N] [--wait S]\n"
            "The SPH node of lahar: joins a run announced by the coordinator (`lahar run`), fills the\n"
            "particle blocks of the scene on a lattice and advances the particles step by step.\n"
            "`lahar run` starts it by itself; start it by hand only with `lahar run --no-spawn`.\n\n"
            "  --lcm-url URL   LCM URL of the run (default: $LCM_DEFAULT_URL, else\n"
            "                  %s, which must only be used inside a private network\n"
            "                  namespace; give ttl=1 to reach another host on an isolated link)\n"
            "  --run-id ID     join only this run (default: the first run announced)\n"
            "  --threads N     OpenMP threads of the particle loops (default: OpenMP's default)\n"
            "  --wait S        seconds to wait for the coordinator's announcement (default 30)\n"
            "  -h, --help      this help\n"
            "Exit status: 0 run finished, 1 output error, 2 setup error, 3 coordinator lost.\n",
            LAHAR_NETNS_URL);
}

int main(int argc, char **argv)
{
    lahar_sph_node_options o = {0};
    o.lcm_url = getenv("LCM_DEFAULT_URL");
    static const struct option opts[] = {
        {"lcm-url", required_argument, NULL, 'u'}, {"run-id", required_argument, NULL, 'r'},
        {"threads", required_argument, NULL, 't'}, {"wait", required_argument, NULL, 'w'},
        {"help", no_argument, NULL, 'h'},          {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        switch (c) {
        case 'u': o.lcm_url = optarg; break;
        case 'r': o.run_id = strtoll(optarg, NULL, 0); break;
        case 't': o.threads = atoi(optarg); break;
        case 'w': o.join_wait_s = atof(optarg); break;
        case 'h': usage(stdout); return 0;
        default: usage(stderr); return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "lahar-sph: unexpected argument '%s'\n", argv[optind]);
        usage(stderr);
        return 2;
    }
    if (!o.lcm_url)
        o.lcm_url = LAHAR_NETNS_URL;
    return lahar_sph_node_run(&o);
}
