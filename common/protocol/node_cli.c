#include "node_cli.h"
#include <getopt.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "auth.h"
#include "msg_check.h"
#include "netns.h"
#include "lahar_stop_t.h"
#include "scene_msg.h"

static void node_usage(FILE *f, const char *prog, const char *about, const char *exit_codes)
{
    fprintf(f,
            "usage: %s [--lcm-url URL] [--run-id ID] [--threads N] [--wait S] [--auth-key FILE]\n"
            "%s\n"
            "`lahar run` starts it by itself; start it by hand only with `lahar run --no-spawn`.\n\n"
            "  --lcm-url URL   LCM URL of the run (default: $LCM_DEFAULT_URL, else\n"
            "                  %s, which must only be used inside a private network\n"
            "                  namespace; give ttl=1 to reach another host on an isolated link)\n"
            "  --run-id ID     join only this run (default: the first run announced)\n"
            "  --threads N     OpenMP threads of the node's loops (default: OpenMP's default)\n"
            "  --wait S        seconds to wait for the coordinator's announcement (default 30)\n"
            "  --auth-key FILE the run's key (the coordinator's --auth-key; also $LAHAR_AUTH_KEY):\n"
            "                  messages without its MAC are dropped\n"
            "  -h, --help      this help\n"
            "%s\n",
            prog, about, LAHAR_NETNS_URL, exit_codes);
}

int lahar_node_parse_args(int argc, char **argv, const char *prog, const char *about, const char *exit_codes,
                          lahar_node_options *o)
{
    o->lcm_url = getenv("LCM_DEFAULT_URL");
    o->run_id = 0;
    o->threads = 0;
    o->join_wait_s = 0.0;
    o->auth_key_path = getenv(LAHAR_AUTH_ENV);
    o->engine = NULL;
    static const struct option opts[] = {
        {"lcm-url", required_argument, NULL, 'u'}, {"run-id", required_argument, NULL, 'r'},
        {"threads", required_argument, NULL, 't'}, {"wait", required_argument, NULL, 'w'},
        {"auth-key", required_argument, NULL, 'k'}, {"help", no_argument, NULL, 'h'}, {NULL, 0, NULL, 0},
    };
    int c;
    while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        switch (c) {
        case 'u': o->lcm_url = optarg; break;
        case 'r': o->run_id = strtoll(optarg, NULL, 0); break;
        case 't': o->threads = atoi(optarg); break;
        case 'w': o->join_wait_s = atof(optarg); break;
        case 'k': o->auth_key_path = optarg; break;
        case 'h': node_usage(stdout, prog, about, exit_codes); return 0;
        default: node_usage(stderr, prog, about, exit_codes); return 2;
        }
    }
    if (optind < argc) {
        fprintf(stderr, "%s: unexpected argument '%s'\n", prog, argv[optind]);
        node_usage(stderr, prog, about, exit_codes);
        return 2;
    }
    if (!o->lcm_url)
        o->lcm_url = LAHAR_NETNS_URL;
    return -1;
}

int lahar_node_connect(const lahar_node_options *o, const char *prog, int role, unsigned want,
                       lahar_transport **t, lahar_link **l)
{
    char err[1024];
    if (o->threads > 0)
        omp_set_num_threads(o->threads);
    *l = NULL;
    *t = lahar_transport_open(o->lcm_url, err, sizeof err);
    if (!*t) {
        fprintf(stderr, "%s: %s\n", prog, err);
        return 2;
    }
    *l = lahar_link_create(*t, role, o->run_id, want, err, sizeof err);
    if (!*l) {
        fprintf(stderr, "%s: %s\n", prog, err);
        lahar_transport_close(*t);
        *t = NULL;
        return 2;
    }
    if (o->auth_key_path && *o->auth_key_path) {
        uint8_t key[LAHAR_AUTH_KEYBYTES];
        if (lahar_auth_key_load(o->auth_key_path, key, err, sizeof err) != 0) {
            fprintf(stderr, "%s: %s\n", prog, err);
            lahar_link_destroy(*l);
            lahar_transport_close(*t);
            *l = NULL;
            *t = NULL;
            return 2;
        }
        lahar_link_set_auth_key(*l, key);
        memset(key, 0, sizeof key);
    }
    return 0;
}

void lahar_node_report_lost(const char *prog, const char *what, int64_t k)
{
    if (lahar_link_parent_gone())
        fprintf(stderr, "%s: lahar, which started this node, has ended (waiting for %s %lld); closing the "
                "output files and exiting\n", prog, what, (long long)k);
    else
        fprintf(stderr, "%s: the coordinator has been silent for %.0f s (waiting for %s %lld); exiting\n", prog,
                LAHAR_NODE_COORDINATOR_SILENCE, what, (long long)k);
}

int lahar_node_wait_step(lahar_link *l, const char *prog, int64_t k, lahar_link_msg *msg, lahar_step_t *step)
{
    int rc = lahar_link_wait(l, LAHAR_ROLE_COORDINATOR, LAHAR_FRAME_T_MSG_STEP, k, -1, msg);
    if (rc == LAHAR_LINK_STOP)
        return 0;
    if (rc == LAHAR_LINK_LOST) {
        lahar_node_report_lost(prog, "step", k);
        return 3;
    }
    if (rc != LAHAR_LINK_OK || LAHAR_MSG_DECODE(lahar_step_t, msg->data, msg->size, step) < 0)
        return 1;
    return -1;
}

int lahar_node_stop_reason(const lahar_link_msg *msg, char *text, size_t n)
{
    lahar_stop_t st;
    if (LAHAR_MSG_DECODE(lahar_stop_t, msg->data, msg->size, &st) < 0)
        return -1;
    int reason = st.reason;
    if (text && n > 0)
        snprintf(text, n, "%s", st.message ? st.message : "");
    lahar_stop_t_decode_cleanup(&st);
    return reason;
}
