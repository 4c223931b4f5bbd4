/* sph.initial_pressure: hydrostatic (sph_node/node/node_fill.c, lahar_sph_node_fill): every particle of a
 * block starts at the density whose EOS pressure is rho0 |g| (h - height), h the block's top (half
 * a spacing above its highest particle centre, = the box's hi along gravity), volume dx^D (its lattice
 * cell), mass rho dx^D.
 * References computed here independently of the node's code, tolerance 1e-12 relative on rho:
 *  - linear EOS (Trujillo-Vela et al. 2020 eq. 3), 2D box 0.4 x 0.2 m, dx 10 mm, gravity -y:
 *    rho = rho0 + rho0 g (h - y) / c0^2;
 *  - Tait EOS (Canelas et al. 2015 eq. 19, gamma 7), 3D, gravity -z, two blocks one above the other, each
 *    with its own free surface: rho = rho0 (1 + gamma g (h - z) / c0^2)^(1/gamma);
 *  - the pressure of those densities by the solver's own EOS (sph_fluid_pressure) is
 *    rho0 g (h - y) to 1e-9 of rho0 g H (round trip);
 *  - initial_pressure: none (the default) keeps rho0 exactly; the option survives the scene
 *    message (common/protocol/scene_msg.c); a misspelt value is refused with the closest name.
 * usage: test_sph_initial_pressure TMP_DIR */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "case.h"
#include "lahar_scene_t.h"
#include "scene_msg.h"
#include "sph_node.h"
#include "test_util.h"

static const double rho0 = 1000.0, g = 9.81, c0 = 20.0;

static int write_case(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    fputs(text, f);
    return fclose(f);
}

/* Load `text` as a case (written to dir/name) or fail the test. */
static int load_case(const char *dir, const char *name, const char *text, lahar_case *c)
{
    char path[1024], err[512];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    if (write_case(path, text) != 0) {
        CHECK(0, "cannot write %s", path);
        return -1;
    }
    if (lahar_case_load_err(path, c, err, sizeof err) != 0) {
        CHECK(0, "%s does not load: %s", name, err);
        return -1;
    }
    return 0;
}

static void test_linear_2d(const char *dir)
{
    static const char *const text = "dimensions: 2\n"
                                    "gravity: [0, -9.81]\n"
                                    "time: {end: 0.1}\n"
                                    "sph:\n"
                                    "  dx: 0.01\n"
                                    "  density: 1000\n"
                                    "  c0: 20\n"
                                    "  initial_pressure: hydrostatic\n"
                                    "  wall_pressure: ghost\n"
                                    "  soil_wall_stress: ghost\n"
                                    "  blocks:\n"
                                    "    - {name: water, box: {lo: [0, 0], hi: [0.4, 0.2]}}\n";
    lahar_case c;
    if (load_case(dir, "ip_linear.yaml", text, &c) != 0)
        return;
    CHECK(c.sph.initial_pressure == LAHAR_SPH_INITIAL_PRESSURE_HYDROSTATIC, "key not read");
    sph_params prm;
    char err[256];
    CHECK(lahar_sph_node_params(&c, &prm, err, sizeof err) == 0, "params: %s", err);
    sph_particles p;
    int64_t n = lahar_sph_node_fill(&p, &c);
    CHECK(n == 40 * 20, "linear: %lld particles, want 800", (long long)n);
    const double H = 0.2, dx = 0.01;
    double worst_rho = 0, worst_p = 0, worst_m = 0;
    for (int64_t i = 0; i < n; i++) {
        double want = rho0 + rho0 * g * (H - p.y[i]) / (c0 * c0);
        worst_rho = fmax(worst_rho, fabs(p.rho[i] / want - 1));
        worst_p = fmax(worst_p, fabs(sph_fluid_pressure(&prm, p.rho[i]) - rho0 * g * (H - p.y[i])) / (rho0 * g * H));
        worst_m = fmax(worst_m, fabs(p.m[i] / (p.rho[i] * dx * dx) - 1));
    }
    printf("linear 2D: %lld particles, rho rel error max %.3g, p round trip %.3g of rho0 g H, mass %.3g\n",
           (long long)n, worst_rho, worst_p, worst_m);
    CHECK(worst_rho <= 1e-12, "linear: rho off the inverse EOS by %g", worst_rho);
    CHECK(worst_p <= 1e-9, "linear: EOS pressure off rho0 g (H - y) by %g of rho0 g H", worst_p);
    CHECK(worst_m <= 1e-12, "linear: mass off rho dx^2 (volume dx^2) by %g", worst_m);

    /* the scene message carries the option to the SPH node */
    lahar_scene_t msg;
    lahar_case back;
    memset(&back, 0, sizeof back);
    CHECK(lahar_scene_msg_from_case(&c, "/tmp", 0, 1, 1, &msg) == 0, "scene message");
    CHECK(lahar_scene_msg_to_case(&msg, &back, err, sizeof err) == 0, "scene message back: %s", err);
    CHECK(back.sph.initial_pressure == LAHAR_SPH_INITIAL_PRESSURE_HYDROSTATIC, "initial_pressure lost in the message");
    CHECK(c.sph.wall_pressure == LAHAR_SPH_WALL_PRESSURE_GHOST && back.sph.wall_pressure == LAHAR_SPH_WALL_PRESSURE_GHOST,
          "wall_pressure not read or lost in the message");
    CHECK(prm.opt.wall_pressure == LAHAR_SPH_WALL_PRESSURE_GHOST, "wall_pressure not passed to the solver");
    CHECK(c.sph.soil_wall_stress == LAHAR_SPH_WALL_PRESSURE_GHOST &&
              back.sph.soil_wall_stress == LAHAR_SPH_WALL_PRESSURE_GHOST,
          "soil_wall_stress not read or lost in the message");
    CHECK(prm.opt.soil_wall_stress == LAHAR_SPH_WALL_PRESSURE_GHOST, "soil_wall_stress not passed to the solver");
    lahar_scene_msg_release(&msg);
    lahar_case_free(&back);
    sph_particles_free(&p);
    lahar_case_free(&c);
}

static void test_tait_3d(const char *dir)
{
    static const char *const text = "dimensions: 3\n"
                                    "gravity: [0, 0, -9.81]\n"
                                    "time: {end: 0.1}\n"
                                    "sph:\n"
                                    "  dx: 0.01\n"
                                    "  density: 1000\n"
                                    "  c0: 20\n"
                                    "  eos: tait\n"
                                    "  gamma: 7\n"
                                    "  initial_pressure: hydrostatic\n"
                                    "  blocks:\n"
                                    "    - {name: low, box: {lo: [0, 0, 0], hi: [0.1, 0.05, 0.1]}}\n"
                                    "    - {name: high, box: {lo: [0, 0, 0.3], hi: [0.1, 0.05, 0.35]}}\n";
    lahar_case c;
    if (load_case(dir, "ip_tait.yaml", text, &c) != 0)
        return;
    sph_params prm;
    char err[256];
    CHECK(lahar_sph_node_params(&c, &prm, err, sizeof err) == 0, "params: %s", err);
    sph_particles p;
    int64_t n = lahar_sph_node_fill(&p, &c);
    CHECK(n == 10 * 5 * 10 + 10 * 5 * 5, "tait: %lld particles, want 750", (long long)n);
    double worst_rho = 0, worst_p = 0, deepest = 0;
    for (int64_t i = 0; i < n; i++) {
        double h = p.z[i] < 0.2 ? 0.1 : 0.35; /* each block's own surface */
        double want = rho0 * pow(1.0 + 7.0 * g * (h - p.z[i]) / (c0 * c0), 1.0 / 7.0);
        worst_rho = fmax(worst_rho, fabs(p.rho[i] / want - 1));
        worst_p = fmax(worst_p, fabs(sph_fluid_pressure(&prm, p.rho[i]) - rho0 * g * (h - p.z[i])) / (rho0 * g * 0.1));
        deepest = fmax(deepest, p.rho[i] / rho0 - 1);
    }
    printf("tait 3D: %lld particles, rho rel error max %.3g, p round trip %.3g of rho0 g H, deepest rho/rho0 - 1 "
           "%.4g\n", (long long)n, worst_rho, worst_p, deepest);
    CHECK(worst_rho <= 1e-12, "tait: rho off the inverse EOS by %g", worst_rho);
    CHECK(worst_p <= 1e-9, "tait: EOS pressure off rho0 g (h - z) by %g of rho0 g H", worst_p);
    CHECK(deepest > 1e-3, "tait: the column is not compressed (%g)", deepest); /* g 0.095 / c0^2 = 2.3e-3 */
    sph_particles_free(&p);
    lahar_case_free(&c);
}

static void test_none(const char *dir)
{
    static const char *const text = "dimensions: 2\n"
                                    "gravity: [0, -9.81]\n"
                                    "time: {end: 0.1}\n"
                                    "sph:\n"
                                    "  dx: 0.01\n"
                                    "  c0: 20\n"
                                    "  blocks:\n"
                                    "    - {name: water, box: {lo: [0, 0], hi: [0.1, 0.1]}}\n";
    lahar_case c;
    if (load_case(dir, "ip_none.yaml", text, &c) != 0)
        return;
    CHECK(c.sph.initial_pressure == LAHAR_SPH_INITIAL_PRESSURE_NONE, "default is not none");
    sph_particles p;
    int64_t n = lahar_sph_node_fill(&p, &c);
    int off = 0;
    for (int64_t i = 0; i < n; i++)
        off += p.rho[i] != rho0;
    CHECK(n == 100 && off == 0, "none: %d of %lld particles not at rest density", off, (long long)n);
    sph_particles_free(&p);
    lahar_case_free(&c);
}

/* A misspelt value is refused with the closest name. */
static void test_bad_value(const char *dir)
{
    static const char *const text = "dimensions: 2\n"
                                    "gravity: [0, -9.81]\n"
                                    "time: {end: 0.1}\n"
                                    "sph:\n"
                                    "  dx: 0.01\n"
                                    "  initial_pressure: hydrostatik\n"
                                    "  blocks:\n"
                                    "    - {name: water, box: {lo: [0, 0], hi: [0.1, 0.1]}}\n";
    char path[1024], err[512] = "";
    snprintf(path, sizeof path, "%s/ip_bad.yaml", dir);
    CHECK(write_case(path, text) == 0, "cannot write %s", path);
    lahar_case c;
    CHECK(lahar_case_load_err(path, &c, err, sizeof err) == LAHAR_EXIT_BAD_INPUT, "a bad initial_pressure loads");
    CHECK(strstr(err, "initial_pressure") && strstr(err, "'hydrostatic'"), "unhelpful message: %s", err);
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : ".";
    test_linear_2d(dir);
    test_tait_3d(dir);
    test_none(dir);
    test_bad_value(dir);
    if (failures)
        printf("%d failure(s)\n", failures);
    else
        printf("ok\n");
    return failures != 0;
}
