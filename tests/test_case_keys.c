/* The key table drives the loader (common/io/case_keys.c): every key of the checked sections is
 * accepted by the loader, its numeric default is what the loader stores, and a value outside the
 * table's range is rejected with the table's message at the key's file:line. A key added to the
 * table but not to the reader (or the other way round) fails here. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "case.h"
#include "case_keys.h"
#include "test_util.h"

/* A small valid 2D case; SECTION's mapping gets "KEY: VALUE" (or nothing when key is NULL). */
static int load_with(const char *section, const char *key, const char *value, lahar_case *c, char *err, size_t n)
{
    char extra[5][160] = {"", "", "", "", ""};
    static const char *const names[] = {"time", "dem", "stability", "checkpoint", "sph"};
    for (int i = 0; i < 5; i++)
        if (key && !strcmp(section, names[i]))
            snprintf(extra[i], sizeof extra[i], "%s: %s%s", key, value, (i == 3 || (i == 0 && !strcmp(key, "end"))) ? "" : ", ");
    /* required keys get their value from `extra` when they are the key under test */
    char end[32] = "end: 0.1", interval[32] = "interval: 0.05", dx[32] = "dx: 0.01, ";
    if (key && !strcmp(section, "time") && !strcmp(key, "end"))
        end[0] = '\0';
    if (key && !strcmp(section, "checkpoint"))
        snprintf(interval, sizeof interval, "%s", strcmp(key, "interval") ? "interval: 0.05, " : "");
    if (key && !strcmp(section, "sph") && !strcmp(key, "dx"))
        dx[0] = '\0';
    char text[2048];
    int len = snprintf(text, sizeof text,
                       "dimensions: 2\n"
                       "time: {%s%s}\n"
                       "materials: {rock: {density: 2650, young: 1e8, restitution: 0.5, friction: 0.5}}\n"
                       "dem: {%sengine: spheropoly}\n"
                       "stability: {%sdensity_band: [0.5, 2.0]}\n"
                       "checkpoint: {%s%s}\n"
                       "bodies: [{name: floor, shape: box, material: rock, motion: fixed, position: [0.05, -0.02],\n"
                       "          size: [0.3, 0.02], radius: 0.001}]\n"
                       "sph: {%s%sblocks: [{box: {lo: [0, 0], hi: [0.1, 0.1]}}]}\n",
                       extra[0], end, extra[1], extra[2], interval, extra[3], dx, extra[4]);
    return lahar_case_load_mem("keys.yaml", text, (size_t)len, c, err, n);
}

int main(void)
{
    static const char *const checked[] = {"time", "dem", "stability", "checkpoint", "sph"};
    char err[1024];
    lahar_case c;
    CHECK(load_with("", NULL, NULL, &c, err, sizeof err) == 0, "the base case does not load: %s", err);
    lahar_case_free(&c);
    /* stored defaults against the table's (keys whose default is a plain number) */
    typedef struct { const char *section, *key; double stored; } stored_default;
    stored_default defaults[16];
    int nd = 0;
    if (load_with("", NULL, NULL, &c, err, sizeof err) == 0) {
        defaults[nd++] = (stored_default){"time", "dt_min", c.dt_min};
        defaults[nd++] = (stored_default){"time", "forces_interval", c.forces_interval};
        defaults[nd++] = (stored_default){"dem", "dt_safety", c.dem_dt_safety};
        defaults[nd++] = (stored_default){"stability", "max_overlap", c.stability.max_overlap};
        defaults[nd++] = (stored_default){"sph", "density", c.sph_density};
        defaults[nd++] = (stored_default){"sph", "h_over_dx", c.sph.h_over_dx};
        defaults[nd++] = (stored_default){"sph", "gamma", c.sph.gamma};
        defaults[nd++] = (stored_default){"sph", "viscosity", c.sph.mu};
        defaults[nd++] = (stored_default){"sph", "alpha", c.sph.alpha};
        defaults[nd++] = (stored_default){"sph", "delta", c.sph.delta};
        defaults[nd++] = (stored_default){"sph", "cfl", c.sph.cfl};
        defaults[nd++] = (stored_default){"sph", "cfl_force", c.sph.cfl_force};
        defaults[nd++] = (stored_default){"sph", "cfl_visc", c.sph.cfl_visc};
        defaults[nd++] = (stored_default){"sph", "sps_cs", c.sph.sps_cs};
        defaults[nd++] = (stored_default){"sph", "shifting", c.sph.shifting};
        lahar_case_free(&c);
    }
    for (int i = 0; i < nd; i++) {
        const lahar_key *k = lahar_key_find(lahar_key_section_find(defaults[i].section), defaults[i].key);
        CHECK(k && lahar_key_default(k) == defaults[i].stored, "%s.%s: the loader stores %g, the table says %s",
              defaults[i].section, defaults[i].key, defaults[i].stored, k ? k->def : "(no entry)");
    }
    int tested = 0;
    for (size_t s = 0; s < sizeof checked / sizeof checked[0]; s++) {
        const lahar_key_section *sec = lahar_key_section_find(checked[s]);
        CHECK(sec != NULL, "no table for section %s", checked[s]);
        for (const lahar_key *k = sec ? sec->keys : NULL; k && k->name; k++) {
            if (k->type != LAHAR_KEY_NUMBER && k->type != LAHAR_KEY_WHOLE)
                continue;
            /* accepted: an unknown key would say so */
            if (load_with(checked[s], k->name, "1e300", &c, err, sizeof err) == 0)
                lahar_case_free(&c);
            CHECK(!strstr(err, "unknown key"), "%s.%s is in the table but the loader does not know it: %s", checked[s],
                  k->name, err);
            if (!(k->range & (LAHAR_KEY_LO | LAHAR_KEY_HI)))
                continue;
            /* just outside the range (below lo, else above hi) */
            double bad = k->range & LAHAR_KEY_LO ? k->lo - 1.0 : k->hi + 1.0;
            if (k->range & LAHAR_KEY_LO_OPEN && k->range & LAHAR_KEY_LO)
                bad = k->lo;
            char value[64], want[512], path[96];
            snprintf(value, sizeof value, "%.17g", bad);
            lahar_key_range_error(k, bad, want, sizeof want);
            snprintf(path, sizeof path, "%s.%s: ", checked[s], k->name);
            int rc = load_with(checked[s], k->name, value, &c, err, sizeof err);
            if (rc == 0)
                lahar_case_free(&c);
            CHECK(rc != 0 && strstr(err, path) && strstr(err, want), "%s = %s: want '%s%s', got '%s'", path, value,
                  path, want, rc ? err : "(loaded)");
            tested++;
        }
    }
    CHECK(tested >= 20, "only %d range checks exercised", tested);
    printf("%d keys' ranges checked against the loader, %d defaults\n", tested, nd);
    return failures != 0;
}
