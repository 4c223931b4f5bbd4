/* lahar: the user's entry point. `lahar run` loads a case, starts the nodes it needs and
 * coordinates the run; `lahar check` runs and evaluates the case's check; `lahar validate` only
 * loads the case; `lahar bench` runs the benchmark driver tools/bench.py. */
#include <errno.h>
#include <getopt.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "case.h"
#include "check.h"
#include "coordinator.h"
#include "dem_engine.h"
#include "estimate.h"
#include "shape_build.h"
#include "auth.h"
#include "netns.h"
#include "output.h"
#include "case_keys.h"

static void usage(FILE *f)
{
    fprintf(f,
            "usage: lahar run CASE.yaml -o OUT [options]     simulate the case, output in OUT\n"
            "       lahar check CASE.yaml -o OUT [options]   simulate, then evaluate the case's check: section\n"
            "       lahar validate CASE.yaml                 load and validate the case only; prints the particle\n"
            "                                                and body count, memory and cost estimates, and a\n"
            "                                                note on each box block dx does not divide and on\n"
            "                                                probes on a body with the penalty wall alone\n"
            "       lahar bench -o OUT [--quick] [options]   run time against error of the validation cases,\n"
            "                                                co-simulation overhead, DEM subcycling: CSV, PNG\n"
            "                                                and OUT/summary.md (`lahar bench --help`)\n"
            "       lahar resume OUT [--time-end T] [options] continue the run in OUT from its newest\n"
            "                                                checkpoint (case section checkpoint:), to its\n"
            "                                                time.end or to T; same options as run\n"
            "       lahar keys [SECTION | --yaml]            every case key: type, unit, default, allowed values\n"
            "                                                (SECTION e.g. sph, time, sph.blocks[]; --yaml: the\n"
            "                                                commented reference, cases/reference.yaml)\n"
            "       lahar keygen FILE                        a new key for --auth-key (mode 0600)\n"
            "       lahar --help | --version\n\n"
            "Options of run and check:\n"
            "  -o, --output OUT   output directory (created): bodies.h5, forces.h5, particles.h5, *.xmf,\n"
            "                     summary.json (and check.json for `check`)\n"
            "  --overwrite        OUT holds an earlier run: remove its files (summary.json, *.h5, *.xmf,\n"
            "                     check.*) first; without it such an OUT is refused (exit 2)\n"
            "  --threads N        OpenMP threads per node (default: OpenMP's default, one per core). When\n"
            "                     they would share cores with other work (the load average of the last\n"
            "                     minute + N > cores + 0.5, and the cores busy over 0.2 s + N too; or other\n"
            "                     lahar runs, N threads each: (runs + 1) N > cores + 0.5), lahar\n"
            "                     says so and starts the nodes with OMP_WAIT_POLICY=passive unless that\n"
            "                     is set (summary.json \"machine\"); with --in-process it runs itself\n"
            "                     again with that policy\n"
            "  --in-process       run the nodes as threads of this process over memq:// (no network;\n"
            "                     gives bitwise the same results as separate processes)\n"
            "  --no-spawn         do not start the nodes: start lahar-dem / lahar-sph yourself with the\n"
            "                     same URL (e.g. on another host); needs --lcm-url, no private namespace;\n"
            "                     `lahar-dem --engine NAME` runs the case with another DEM engine\n"
            "  --lcm-url URL      use this LCM URL instead of a private network namespace (also taken\n"
            "                     from $LCM_DEFAULT_URL). Set ttl yourself (ttl=0: this host only) and\n"
            "                     recv_buf_size=8388608\n"
            "  --wait S           seconds to wait for the nodes to join (default 30)\n"
            "  --auth-key FILE    authenticate every message with this key (also $LAHAR_AUTH_KEY):\n"
            "                     for runs across machines; the nodes need the same --auth-key.\n"
            "                     Forged, altered and replayed messages are dropped and counted in\n"
            "                     summary.json (auth). Make a key with `lahar keygen FILE`\n"
            "  --node-timeout S   a node silent for S seconds is lost (default 2). A node lahar started\n"
            "                     that is silent but still using CPU is waited for up to 120 s more\n"
            "                     (an overloaded machine); a node whose process ended is lost at once\n"
            "  -q, --quiet        no progress line and no closing hints\n"
            "  --progress-every S when stderr is not a terminal (a log file, a pipe, a batch job): a\n"
            "                     progress line (sim time, %% done, steps/s, elapsed, ETA) every S seconds\n"
            "                     of wall time (default 60; 0: none). On a terminal one line is updated\n"
            "                     in place instead\n"
            "  --allow-large      run a case whose estimated memory (`lahar validate` prints it) exceeds\n"
            "                     this machine's; without it such a run is refused (exit 2)\n"
            "  --time-end T       (resume) end the resumed run at T s instead of the case's time.end\n"
            "  --evaluate-only    (check) do not simulate: evaluate the check: section on the output\n"
            "                     already in OUT (e.g. after changing a bound, or of a run on a cluster)\n\n"
            "By default lahar creates a private network namespace (unshare of user + network namespaces)\n"
            "with multicast on its loopback and uses %s\n"
            "inside it: nothing leaves the machine and two runs never hear each other. The nodes are\n"
            "started next to this executable (lahar-dem, lahar-sph) and die with it.\n\n"
            "Exit status: 0 finished (check: all metrics pass), 1 a node reported an error or a check\n"
            "metric failed, 2 bad input or setup failure, 3 a node was lost (--node-timeout).\n",
            LAHAR_NETNS_URL);
}

/* `lahar bench ARGS`: exec python3 tools/bench.py --lahar THIS_EXECUTABLE ARGS (the driver starts
 * `lahar check` runs of case variants; Python for its CSV and plots). */
static int bench_exec(int argc, char **argv)
{
    const char *py = getenv("LAHAR_PYTHON");
    if (!py || !*py)
        py = "python3";
    static char self[PATH_MAX], script[PATH_MAX];
    ssize_t n = readlink("/proc/self/exe", self, sizeof self - 1);
    if (n <= 0)
        snprintf(self, sizeof self, "%s", argv[0]);
    else
        self[n] = '\0';
    snprintf(script, sizeof script, "%s/bench.py", LAHAR_TOOLS_DIR);
    char **av = calloc((size_t)argc + 4, sizeof *av);
    if (!av)
        return 2;
    int k = 0;
    av[k++] = (char *)py;
    av[k++] = script;
    av[k++] = "--lahar";
    av[k++] = self;
    for (int i = 2; i < argc; i++)
        av[k++] = argv[i];
    av[k] = NULL;
    execvp(py, av);
    fprintf(stderr, "lahar bench: cannot run %s %s: %s (install python3, python3-numpy, python3-matplotlib, "
                    "python3-yaml, or set LAHAR_PYTHON)\n",
            py, script, strerror(errno));
    free(av);
    return 2;
}

/* A whole number in [lo, hi] for option `opt`, or exit 2 naming the option and what it takes. */
static int parse_int_option(const char *cmd, const char *opt, const char *s, long lo, long hi, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (errno || end == s || *end != '\0' || v < lo || v > hi) {
        fprintf(stderr, "lahar %s: %s takes a whole number from %ld to %ld (got '%s')\n", cmd, opt, lo, hi, s);
        return -1;
    }
    *out = (int)v;
    return 0;
}

/* A number in (lo, hi] of seconds for option `opt` (or 0 when zero_off: the option turned off), or
 * -1 with the message. */
static int parse_seconds_option(const char *cmd, const char *opt, const char *s, double lo, double hi, int zero_off,
                                double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end != '\0' || !((v > lo && v <= hi) || (zero_off && v == 0.0))) {
        fprintf(stderr, "lahar %s: %s takes a number of seconds above %g and at most %g%s (got '%s')\n", cmd, opt, lo,
                hi, zero_off ? ", or 0 for none" : "", s);
        return -1;
    }
    *out = v;
    return 0;
}

/* "1.2 GB" */
static const char *human_bytes(double b, char *buf, size_t n)
{
    const char *unit[] = {"B", "kB", "MB", "GB", "TB"};
    int u = 0;
    while (b >= 1000.0 && u < 4) {
        b /= 1000.0;
        u++;
    }
    snprintf(buf, n, "%.3g %s", b, unit[u]);
    return buf;
}

/* What the case will cost (coordinator/estimate.h), for `validate`. */
static void print_estimate(const lahar_case *cs, const lahar_estimate *e)
{
    char mem[32], machine[32];
    printf("  %lld particles%s (%lld soil%s), %d bodies\n", (long long)e->particles, e->exact ? "" : " at most",
           (long long)e->soil_particles,
           e->exact ? "" : "; the blocks' lattices: too many points to count with the bodies cut out", e->bodies);
    if (e->inflow_particles > 0)
        printf("  inlets: room for up to %lld more particles (inlets[k].max_particles)\n", (long long)e->inflow_particles);
    printf("  memory: about %s for the run (machine: %s)\n", human_bytes(e->bytes, mem, sizeof mem),
           human_bytes(lahar_estimate_machine_bytes(), machine, sizeof machine));
    if (e->particles > 0)
        printf("  cost: at least %.3g steps to t = %g s (SPH step <= %.3g s by the CFL limit), %.3g particle-steps "
               "(about %.2g core-hours at 1e6 particle-steps/s)\n",
               e->steps, cs->t_end, e->dt, e->particle_steps, e->particle_steps / 1e6 / 3600.0);
}

/* A box block whose sides are not whole multiples of sph.dx holds less than it says (the lattice
 * takes whole spacings per side): a note for each one short by more than 1 % of its volume, with
 * the dx that would fill each short side. To stdout for `validate`, stderr otherwise. */
static void note_block_fill(FILE *out, const lahar_case *cs)
{
    const double dx = cs->sph_dx;
    for (int i = 0; i < cs->nblock; i++) {
        const lahar_particle_block *b = &cs->blocks[i];
        double filled[3];
        const double fraction = lahar_particle_block_box_filled(b, cs->dim, dx, filled);
        if (b->kind != LAHAR_BLOCK_BOX || !(fraction < 0.99))
            continue;
        char side[96] = "", fill[96] = "", hint[256] = "";
        for (int a = 0; a < cs->dim; a++) {
            const double L = b->hi[a] - b->lo[a];
            snprintf(side + strlen(side), sizeof side - strlen(side), "%s%g", a ? " x " : "", L);
            snprintf(fill + strlen(fill), sizeof fill - strlen(fill), "%s%g", a ? " x " : "", filled[a]);
            if (filled[a] < (1.0 - 1e-9) * L) {
                const double n = ceil(L / dx - 1e-9);
                snprintf(hint + strlen(hint), sizeof hint - strlen(hint), "%s%c %g = %.0f x %.5g", hint[0] ? ", " : "",
                         "xyz"[a], L, n, L / n);
            }
        }
        fprintf(out, "%s: note: sph.blocks[%d] '%s' is %s m, but at dx = %g its particles fill %s m, %.1f %% of its "
                     "volume (the lattice takes whole spacings per side). A dx that divides a side fills it: %s\n",
                cs->path, i, b->name, side, dx, fill, 100.0 * fraction, hint);
    }
}

/* Pressure probes on a body read the water's pressure next to it (Adami et al. 2012 eq. 27); with
 * the penalty wall alone the penalty force, not that pressure, stops the water at the wall, and the
 * probes read far below the load the body carries (a jet on a plate at b/dx = 20: 41 % under the
 * stagnation pressure while the plate's force is within 1 %; docs/bench/jet_impingement.md). One
 * note naming the first such probe. To stdout for `validate`, stderr otherwise. */
static void note_wall_probes(FILE *out, const lahar_case *cs)
{
    if (cs->sph.wall_pressure != LAHAR_SPH_WALL_PRESSURE_PENALTY)
        return;
    int n = 0, first = -1;
    for (int i = 0; i < cs->nprobe; i++)
        if (cs->probes[i].kind == LAHAR_PROBE_PRESSURE && cs->probes[i].body >= 0) {
            n++;
            if (first < 0)
                first = i;
        }
    if (n == 0)
        return;
    fprintf(out, "%s: note: probes[%d] '%s'%s reads the pressure on body '%s' from the water next to it, but with "
                 "sph.wall_pressure: penalty (the default) the penalty force stops the water there and such probes "
                 "read far below the load the body carries (41 %% low for a jet on a plate, "
                 "docs/bench/jet_impingement.md). Set sph.wall_pressure: ghost and sph.penalty_stiffness: acoustic\n",
            cs->path, first, cs->probes[first].name, n > 1 ? " (and the other probes on bodies)" : "",
            cs->bodies[cs->probes[first].body].name);
}

/* A run whose estimated memory exceeds the machine's is refused (exit 2) unless --allow-large. */
static int check_memory(const char *cmd, const lahar_case *cs, lahar_estimate *e)
{
    double machine = lahar_estimate_machine_bytes();
    if (machine <= 0.0 || e->bytes <= machine)
        return 0;
    if (!e->exact) { /* the lattice's upper bound is over: count the particles before refusing */
        lahar_estimate_case(cs, LAHAR_ESTIMATE_COUNT_MAX, e);
        if (e->bytes <= machine)
            return 0;
    }
    char mem[32], mach[32];
    fprintf(stderr, "lahar %s: %s needs about %s of memory (%s%lld particles) but this machine has %s; use a larger "
                    "sph.dx (memory falls as dx^-%d), or --allow-large to run it anyway\n", cmd, cs->path,
            human_bytes(e->bytes, mem, sizeof mem), e->exact ? "" : "at most ", (long long)e->particles,
            human_bytes(machine, mach, sizeof mach), cs->dim);
    return -1;
}

/* The DEM engine the case names must exist in this build (dem_node/engines/dem_engine_registry.c) and
 * accept the case (its check_case): said at validation, with the case's file and line, not when the
 * DEM node starts. */
static int check_dem_engine(const lahar_case *cs)
{
    const lahar_dem_engine_ops *eng = lahar_dem_engine_find(cs->dem_engine);
    if (!eng) {
        fprintf(stderr, "%s:%d: dem.engine: unknown DEM engine '%s'; engines in this build: %s\n", cs->path,
                cs->dem_engine_line, cs->dem_engine, lahar_dem_engine_names());
        return -1;
    }
    /* the engine validates what is its own (the shapes and sections it can run) */
    char err[1024];
    if (cs->nbody > 0 && eng->check_case && eng->check_case(cs, err, sizeof err) != 0) {
        fprintf(stderr, "%s:%d: dem.engine: %s cannot run this case: %s\n", cs->path, cs->dem_engine_line,
                cs->dem_engine, err);
        return -1;
    }
    return 0;
}

/* What a step of main returns when the command goes on; any other value is its exit status. */
#define GO_ON (-1)

/* `lahar keys [SECTION | --yaml]` */
static int keys_command(int argc, char **argv)
{
    if (argc > 3) {
        fprintf(stderr, "usage: lahar keys [SECTION | --yaml]\n");
        return 2;
    }
    if (argc == 3 && !strcmp(argv[2], "--yaml")) {
        lahar_keys_print_yaml(stdout);
        return 0;
    }
    return lahar_keys_print(stdout, argc == 3 ? argv[2] : NULL) == 0 ? 0 : 2;
}

/* `lahar keygen FILE` */
static int keygen_command(int argc, char **argv)
{
    char err[512];
    if (argc != 3 || argv[2][0] == '-') {
        fprintf(stderr, "usage: lahar keygen FILE   (a new key for authenticated runs, mode 0600)\n");
        return 2;
    }
    if (lahar_auth_keygen(argv[2], err, sizeof err) != 0) {
        fprintf(stderr, "lahar keygen: %s\n", err);
        return 2;
    }
    printf("lahar keygen: wrote a new key to %s; copy it (privately) to every host of the run and give it "
           "to lahar, lahar-dem and lahar-sph with --auth-key %s\n", argv[2], argv[2]);
    return 0;
}

/* The commands without a case or the run options (help, --version, bench, keys, keygen): their
 * exit status, or GO_ON for any other command. */
static int other_command(int argc, char **argv)
{
    const char *cmd = argv[1];
    if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help") || !strcmp(cmd, "help")) {
        usage(stdout);
        return 0;
    }
    if (!strcmp(cmd, "--version")) {
        printf("lahar %s\n", LAHAR_VERSION);
        return 0;
    }
    if (!strcmp(cmd, "bench"))
        return bench_exec(argc, argv);
    if (!strcmp(cmd, "keys"))
        return keys_command(argc, argv);
    if (!strcmp(cmd, "keygen"))
        return keygen_command(argc, argv);
    return GO_ON;
}

/* run, check, validate or resume, and the options given that are not lahar_coord_options */
typedef struct {
    const char *cmd;
    int is_check, is_validate, is_resume;
    int evaluate_only, allow_large;
} cli_command;

/* Which of run, check, validate and resume cmd is; -1 (and the usage) for none of them. */
static int identify_command(const char *cmd, cli_command *a)
{
    memset(a, 0, sizeof *a);
    a->cmd = cmd;
    int is_run = !strcmp(cmd, "run");
    a->is_check = !strcmp(cmd, "check");
    a->is_validate = !strcmp(cmd, "validate");
    a->is_resume = !strcmp(cmd, "resume");
    if (!is_run && !a->is_check && !a->is_validate && !a->is_resume) {
        fprintf(stderr, "lahar: unknown command '%s' (run, check, validate, resume, bench, keys, keygen)\n", cmd);
        usage(stderr);
        return -1;
    }
    return 0;
}

/* The options after the command (getopt_long from argv[2]; optind is then at the first operand).
 * A value out of range ends lahar with status 2 here, before a case is read. GO_ON, or the exit
 * status (0 for --help). */
static int parse_options(int argc, char **argv, cli_command *a, lahar_coord_options *o)
{
    const char *cmd = a->cmd;
    memset(o, 0, sizeof *o);
    o->argv0 = argv[0];
    o->progress_every_s = 60.0;
    static const struct option opts[] = {
        {"output", required_argument, NULL, 'o'}, {"threads", required_argument, NULL, 't'},
        {"in-process", no_argument, NULL, 'i'},   {"no-spawn", no_argument, NULL, 'n'},
        {"lcm-url", required_argument, NULL, 'u'}, {"wait", required_argument, NULL, 'w'},
        {"quiet", no_argument, NULL, 'q'},        {"help", no_argument, NULL, 'h'},
        {"evaluate-only", no_argument, NULL, 'e'}, {"allow-large", no_argument, NULL, 'L'},
        {"node-timeout", required_argument, NULL, 'T'}, {"overwrite", no_argument, NULL, 'O'},
        {"auth-key", required_argument, NULL, 'K'}, {"time-end", required_argument, NULL, 'E'},
        {"progress-every", required_argument, NULL, 'P'},
        {NULL, 0, NULL, 0},
    };
    optind = 2;
    int c;
    while ((c = getopt_long(argc, argv, "o:qh", opts, NULL)) != -1) {
        switch (c) {
        case 'o': o->outdir = optarg; break;
        case 't':
            if (parse_int_option(cmd, "--threads", optarg, 1, 1024, &o->threads) != 0)
                return 2;
            break;
        case 'i': o->in_process = 1; break;
        case 'n': o->no_spawn = 1; break;
        case 'u': o->lcm_url = optarg; break;
        case 'w':
            if (parse_seconds_option(cmd, "--wait", optarg, 0.0, 86400.0, 0, &o->join_wait_s) != 0)
                return 2;
            break;
        case 'q': o->quiet = 1; break;
        case 'P': /* 0: no progress lines */
            if (parse_seconds_option(cmd, "--progress-every", optarg, 0.0, 86400.0, 1, &o->progress_every_s) != 0)
                return 2;
            break;
        case 'e': a->evaluate_only = 1; break;
        case 'L': a->allow_large = 1; break;
        case 'O': o->overwrite = 1; break;
        case 'K': o->auth_key_path = optarg; break;
        case 'E':
            if (!a->is_resume) {
                fprintf(stderr, "lahar %s: --time-end belongs to `lahar resume` (the case's time.end sets a run's end)\n",
                        cmd);
                return 2;
            }
            if (parse_seconds_option(cmd, "--time-end", optarg, 0.0, 1e12, 0, &o->resume_t_end) != 0)
                return 2;
            break;
        case 'T':
            if (parse_seconds_option(cmd, "--node-timeout", optarg, 0.0, 3600.0, 0, &o->node_timeout_s) != 0)
                return 2;
            break;
        case 'h': usage(stdout); return 0;
        default: usage(stderr); return 2;
        }
    }
    return GO_ON;
}

/* `lahar resume OUT`: the case the run was started with, kept in OUT/checkpoints, run on from the
 * newest checkpoint. */
static int resume_command(int argc, char **argv, lahar_coord_options *o)
{
    if (optind != argc - 1 || o->outdir) {
        fprintf(stderr, "lahar resume: expected exactly one output directory (lahar resume OUT [options])\n");
        return 2;
    }
    o->outdir = argv[optind];
    o->resume = 1;
    if (o->in_process && (o->no_spawn || o->lcm_url)) {
        fprintf(stderr, "lahar resume: --in-process runs without network; it excludes --no-spawn and --lcm-url\n");
        return 2;
    }
    lahar_case rc;
    int st = lahar_coord_resume_case(o->outdir, &rc);
    if (st != 0)
        return st;
    st = check_dem_engine(&rc) != 0 ? LAHAR_EXIT_BAD_INPUT : lahar_coord_run(&rc, o);
    lahar_case_free(&rc);
    return st;
}

/* The operands and the options that go together, for run, check and validate: -1 (exit 2) after
 * saying what is wrong. */
static int check_case_arguments(const cli_command *a, int argc, const lahar_coord_options *o)
{
    const char *cmd = a->cmd;
    if (optind != argc - 1) {
        fprintf(stderr, "lahar %s: expected exactly one case file\n", cmd);
        usage(stderr);
        return -1;
    }
    if (!a->is_validate && !o->outdir) {
        fprintf(stderr, "lahar %s: missing -o OUT (output directory)\n", cmd);
        return -1;
    }
    if (o->outdir && !o->outdir[0]) { /* -o "" (an unset shell variable) */
        fprintf(stderr, "lahar %s: -o is empty; give the output directory's name, e.g. -o out/run\n", cmd);
        return -1;
    }
    if (a->evaluate_only && !a->is_check) {
        fprintf(stderr, "lahar %s: --evaluate-only belongs to `lahar check`\n", cmd);
        return -1;
    }
    if (o->in_process && (o->no_spawn || o->lcm_url)) {
        fprintf(stderr, "lahar %s: --in-process runs without network; it excludes --no-spawn and --lcm-url\n", cmd);
        return -1;
    }
    return 0;
}

/* `lahar validate`: the case is valid (it was loaded); what it holds and will cost, on stdout. */
static int validate_case(const char *case_path, const lahar_case *cs)
{
    lahar_estimate est;
    lahar_estimate_case(cs, LAHAR_ESTIMATE_COUNT_MAX, &est);
    printf("%s: valid (%dD, %d bodies, %d particle blocks, t_end = %g s)\n", case_path, cs->dim, cs->nbody,
           cs->nblock, cs->t_end);
    print_estimate(cs, &est);
    note_block_fill(stdout, cs);
    note_wall_probes(stdout, cs);
    return 0;
}

/* `lahar run` and `lahar check`: the run (not with --evaluate-only; refused when it would not fit
 * in memory, unless --allow-large, and not judged for nodes on other hosts), then for `check` the
 * evaluation of a finished run. */
static int run_case(const cli_command *a, const char *case_path, const lahar_case *cs, const lahar_coord_options *o)
{
    int status = 0;
    if (!a->evaluate_only) {
        lahar_estimate est;
        lahar_estimate_case(cs, LAHAR_ESTIMATE_COUNT_RUN, &est);
        if (!o->no_spawn && !a->allow_large && check_memory(a->cmd, cs, &est) != 0)
            return LAHAR_EXIT_BAD_INPUT;
        note_block_fill(stderr, cs);
        note_wall_probes(stderr, cs);
        status = lahar_coord_run(cs, o);
    }
    if (a->is_check && status == 0) {
        if (!cs->check.enabled) {
            fprintf(stderr, "lahar check: %s has no check: section\n", case_path);
            status = 2;
        } else {
            status = lahar_check_evaluate(cs, o->outdir);
        }
    }
    return status;
}

/* run, check, validate: the case loaded and validated (bad input: exit 2 before anything runs),
 * then the command. */
static int case_command(const cli_command *a, int argc, char **argv, const lahar_coord_options *o)
{
    if (check_case_arguments(a, argc, o) != 0)
        return 2;
    const char *case_path = argv[optind];
    lahar_case cs;
    if (lahar_case_load(case_path, &cs) != 0)
        return LAHAR_EXIT_BAD_INPUT;
    if (check_dem_engine(&cs) != 0) {
        lahar_case_free(&cs);
        return LAHAR_EXIT_BAD_INPUT;
    }
    const int status = a->is_validate ? validate_case(case_path, &cs) : run_case(a, case_path, &cs, o);
    lahar_case_free(&cs);
    return lahar_output_exit(status); /* HDF5's clean-up at exit would crash on a file that failed to close */
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        usage(stderr);
        return 2;
    }
    int status = other_command(argc, argv);
    if (status != GO_ON)
        return status;
    cli_command a;
    if (identify_command(argv[1], &a) != 0)
        return 2;
    lahar_coord_options o;
    status = parse_options(argc, argv, &a, &o);
    if (status != GO_ON)
        return status;
    if (!a.is_validate && !a.evaluate_only)
        lahar_coord_in_process_wait_policy(argv, &o);
    return a.is_resume ? resume_command(argc, argv, &o) : case_command(&a, argc, argv, &o);
}
