/* Terrain input: ESRI ASCII grids, CSV profiles, and the shapes and blocks built from them
 * (terrain.h). */
#include "errmsg.h"
#include "terrain.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "shape_build.h"

/* --- ESRI ASCII grid -------------------------------------------------------------------------- */

/* Whitespace-separated tokens of a file, with the line each starts on. */
typedef struct {
    FILE *fp;
    int line;
    char tok[128];
    int tok_line;
} tokens;

/* Next token into t->tok; 0, 1 at the end of the file, -1 if a token is too long. */
static int tok_next(tokens *t)
{
    int ch;
    do {
        ch = fgetc(t->fp);
        if (ch == '\n')
            t->line++;
    } while (ch != EOF && isspace(ch));
    if (ch == EOF)
        return 1;
    t->tok_line = t->line;
    size_t n = 0;
    while (ch != EOF && !isspace(ch)) {
        if (n + 1 >= sizeof t->tok)
            return -1;
        t->tok[n++] = (char)ch;
        ch = fgetc(t->fp);
    }
    if (ch == '\n')
        t->line++;
    t->tok[n] = '\0';
    return 0;
}

static int parse_double(const char *s, double *v)
{
    char *end;
    errno = 0;
    *v = strtod(s, &end);
    return end != s && *end == '\0' && errno != ERANGE && isfinite(*v) ? 0 : -1;
}

void lahar_heightmap_free(lahar_heightmap *h)
{
    if (!h)
        return;
    free(h->z);
    memset(h, 0, sizeof *h);
}

int lahar_heightmap_valid(const lahar_heightmap *h, int i, int j)
{
    return h->z[(size_t)i * h->ncols + j] != h->nodata;
}

/* The header keys of an ESRI ASCII grid, in the order of asc_header.val. */
enum { ASC_NCOLS, ASC_NROWS, ASC_XLL, ASC_YLL, ASC_CELL, ASC_NODATA, ASC_NKEY };

typedef struct {
    double val[ASC_NKEY];
    int have[ASC_NKEY];
    int xcenter, ycenter; /* xllcenter / yllcenter instead of the corner */
} asc_header;

/* The header: KEY VALUE pairs until the first token that is a number (left in t). */
static int asc_read_header(tokens *t, const char *path, asc_header *hd, char *err, size_t errlen)
{
    memset(hd, 0, sizeof *hd);
    for (;;) {
        int rc = tok_next(t);
        if (rc != 0) {
            lahar_errf(err, errlen, "%s:%d: %s; an ESRI ASCII grid starts with ncols, nrows, xllcorner, yllcorner, "
                     "cellsize (and NODATA_value) followed by the values", path, t->line,
                     rc > 0 ? "the file ends in the header" : "a word longer than 127 characters");
            return -1;
        }
        double num;
        if (parse_double(t->tok, &num) == 0)
            break;
        static const char *const names[] = {"ncols", "nrows", "xllcorner", "yllcorner", "cellsize", "nodata_value"};
        int k = -1;
        for (int i = 0; i < ASC_NKEY; i++)
            if (strcasecmp(t->tok, names[i]) == 0)
                k = i;
        if (strcasecmp(t->tok, "xllcenter") == 0)
            k = ASC_XLL, hd->xcenter = 1;
        if (strcasecmp(t->tok, "yllcenter") == 0)
            k = ASC_YLL, hd->ycenter = 1;
        if (k < 0) {
            lahar_errf(err, errlen, "%s:%d: unknown header key '%s'; the header keys are ncols, nrows, xllcorner (or "
                     "xllcenter), yllcorner (or yllcenter), cellsize, NODATA_value", path, t->tok_line, t->tok);
            return -1;
        }
        if (hd->have[k]) {
            lahar_errf(err, errlen, "%s:%d: header key '%s' given twice; keep one", path, t->tok_line, t->tok);
            return -1;
        }
        int kl = t->tok_line;
        char key[128];
        snprintf(key, sizeof key, "%s", t->tok);
        if (tok_next(t) != 0 || parse_double(t->tok, &hd->val[k]) != 0 || t->tok_line != kl) {
            lahar_errf(err, errlen, "%s:%d: header key '%s' needs a number after it on the same line", path, kl, key);
            return -1;
        }
        hd->have[k] = 1;
    }
    static const char *const need[] = {"ncols", "nrows", "xllcorner", "yllcorner", "cellsize"};
    for (int k = 0; k < ASC_CELL + 1; k++)
        if (!hd->have[k]) {
            lahar_errf(err, errlen, "%s:%d: the header has no '%s'; add a line `%s VALUE` before the values", path,
                     t->tok_line, need[k], need[k]);
            return -1;
        }
    const double *val = hd->val;
    if (!(val[ASC_NCOLS] >= 2 && val[ASC_NCOLS] == floor(val[ASC_NCOLS]) && val[ASC_NROWS] >= 2 &&
          val[ASC_NROWS] == floor(val[ASC_NROWS]) && val[ASC_NCOLS] * val[ASC_NROWS] <= 1e8)) {
        lahar_errf(err, errlen, "%s: ncols and nrows must be whole numbers >= 2 (got %g and %g, at most 1e8 values)",
                 path, val[ASC_NCOLS], val[ASC_NROWS]);
        return -1;
    }
    if (!(val[ASC_CELL] > 0)) {
        lahar_errf(err, errlen, "%s: cellsize must be > 0 m (got %g)", path, val[ASC_CELL]);
        return -1;
    }
    return 0;
}

/* The nrows x ncols values, the first already in t, rows from the north; h->z stores them from the
 * south (row 0 at y0). Nothing may follow them. */
static int asc_read_values(tokens *t, const char *path, lahar_heightmap *h, char *err, size_t errlen)
{
    const size_t total = (size_t)h->ncols * h->nrows;
    int rc;
    for (size_t k = 0; k < total; k++) {
        if (k > 0 && (rc = tok_next(t)) != 0) {
            lahar_errf(err, errlen, "%s:%d: %s after %zu of the %d x %d = %zu values (row %zu from the north); "
                     "each of the nrows rows needs ncols values", path, rc > 0 ? t->tok_line : t->line,
                     rc > 0 ? "the file ends" : "a word longer than 127 characters", k, h->nrows, h->ncols, total,
                     k / (size_t)h->ncols + 1);
            return -1;
        }
        double z;
        if (parse_double(t->tok, &z) != 0) {
            lahar_errf(err, errlen, "%s:%d: '%s' is not a number (value %zu: row %zu from the north, column %zu); "
                     "the values are elevations in m, NODATA_value where there is none", path, t->tok_line, t->tok,
                     k + 1, k / (size_t)h->ncols + 1, k % (size_t)h->ncols + 1);
            return -1;
        }
        int row = (int)(k / (size_t)h->ncols), col = (int)(k % (size_t)h->ncols);
        h->z[(size_t)(h->nrows - 1 - row) * h->ncols + col] = z;
    }
    if (tok_next(t) == 0) {
        lahar_errf(err, errlen, "%s:%d: more values than nrows x ncols = %zu ('%s'); check ncols and nrows", path,
                 t->tok_line, total, t->tok);
        return -1;
    }
    return 0;
}

int lahar_heightmap_read_asc(const char *path, lahar_heightmap *h, char *err, size_t errlen)
{
    memset(h, 0, sizeof *h);
    FILE *fp = lahar_fopen_input(path, "r");
    if (!fp) {
        lahar_errf(err, errlen, "%s: cannot open the grid file: %s; check the path", path, strerror(errno));
        return -1;
    }
    tokens t = {fp, 1, "", 1};
    asc_header hd;
    int rc = asc_read_header(&t, path, &hd, err, errlen);
    if (rc == 0) {
        const double *val = hd.val;
        h->ncols = (int)val[ASC_NCOLS];
        h->nrows = (int)val[ASC_NROWS];
        h->cellsize = val[ASC_CELL];
        h->x0 = val[ASC_XLL] + (hd.xcenter ? 0.0 : 0.5 * val[ASC_CELL]);
        h->y0 = val[ASC_YLL] + (hd.ycenter ? 0.0 : 0.5 * val[ASC_CELL]);
        h->nodata = hd.have[ASC_NODATA] ? val[ASC_NODATA] : -9999.0;
        h->z = malloc((size_t)h->ncols * h->nrows * sizeof *h->z);
        if (!h->z) {
            lahar_errf(err, errlen, "%s: out of memory for a %d x %d grid", path, h->ncols, h->nrows);
            rc = -1;
        }
    }
    if (rc == 0)
        rc = asc_read_values(&t, path, h, err, errlen);
    fclose(fp);
    if (rc != 0)
        lahar_heightmap_free(h);
    return rc;
}

int lahar_heightmap_shape(const lahar_heightmap *h, double radius, lahar_shape *s, char *err, size_t errlen)
{
    memset(s, 0, sizeof *s);
    const int nc = h->ncols, nr = h->nrows;
    int *vid = malloc((size_t)nc * nr * sizeof *vid);
    int ncell = 0;
    if (!vid) {
        lahar_errf(err, errlen, "out of memory for the terrain");
        return -1;
    }
    for (size_t k = 0; k < (size_t)nc * nr; k++)
        vid[k] = -1;
    for (int i = 0; i + 1 < nr; i++)
        for (int j = 0; j + 1 < nc; j++)
            if (lahar_heightmap_valid(h, i, j) && lahar_heightmap_valid(h, i, j + 1) &&
                lahar_heightmap_valid(h, i + 1, j) && lahar_heightmap_valid(h, i + 1, j + 1)) {
                ncell++;
                vid[(size_t)i * nc + j] = vid[(size_t)i * nc + j + 1] = vid[(size_t)(i + 1) * nc + j] =
                    vid[(size_t)(i + 1) * nc + j + 1] = 0;
            }
    if (ncell < 2) {
        free(vid);
        lahar_errf(err, errlen, "the grid has %d cell(s) whose four corners all have data; a terrain needs at least 2",
                 ncell);
        return -1;
    }
    int nv = 0;
    for (size_t k = 0; k < (size_t)nc * nr; k++)
        if (vid[k] == 0)
            vid[k] = nv++;
    double(*v)[3] = malloc((size_t)nv * sizeof *v);
    int *fs = malloc(((size_t)2 * ncell + 1) * sizeof *fs), *fv = malloc((size_t)6 * ncell * sizeof *fv);
    int rc = -1;
    if (v && fs && fv) {
        for (int i = 0; i < nr; i++)
            for (int j = 0; j < nc; j++) {
                int id = vid[(size_t)i * nc + j];
                if (id >= 0) {
                    v[id][0] = h->x0 + j * h->cellsize;
                    v[id][1] = h->y0 + i * h->cellsize;
                    v[id][2] = h->z[(size_t)i * nc + j];
                }
            }
        int nf = 0;
        for (int i = 0; i + 1 < nr; i++)
            for (int j = 0; j + 1 < nc; j++) {
                int a = vid[(size_t)i * nc + j], b = vid[(size_t)i * nc + j + 1], c = vid[(size_t)(i + 1) * nc + j + 1],
                    d = vid[(size_t)(i + 1) * nc + j];
                if (a < 0 || b < 0 || c < 0 || d < 0 || !lahar_heightmap_valid(h, i, j) ||
                    !lahar_heightmap_valid(h, i, j + 1) || !lahar_heightmap_valid(h, i + 1, j) ||
                    !lahar_heightmap_valid(h, i + 1, j + 1))
                    continue;
                /* (a, b, c) and (a, c, d): counter-clockwise seen from above, normal up */
                const int tri[2][3] = {{a, b, c}, {a, c, d}};
                for (int q = 0; q < 2; q++, nf++) {
                    fs[nf] = 3 * nf;
                    for (int k = 0; k < 3; k++)
                        fv[3 * nf + k] = tri[q][k];
                }
            }
        fs[nf] = 3 * nf;
        rc = lahar_shape_make_polyhedron(s, (const double(*)[3])v, nv, fs, fv, nf, radius, err, errlen);
    } else {
        lahar_errf(err, errlen, "out of memory for the terrain");
    }
    free(v), free(fs), free(fv), free(vid);
    return rc;
}

/* Slope factor sqrt(1 + |grad z|^2) at node (i, j): central differences, one-sided at the edges. */
static double grid_slope_factor(const lahar_heightmap *h, int i, int j)
{
    const int nc = h->ncols, nr = h->nrows;
    int j0 = j > 0 ? j - 1 : j, j1 = j + 1 < nc ? j + 1 : j, i0 = i > 0 ? i - 1 : i, i1 = i + 1 < nr ? i + 1 : i;
    double gx = (h->z[(size_t)i * nc + j1] - h->z[(size_t)i * nc + j0]) / ((j1 - j0) * h->cellsize);
    double gy = (h->z[(size_t)i1 * nc + j] - h->z[(size_t)i0 * nc + j]) / ((i1 - i0) * h->cellsize);
    return sqrt(1.0 + gx * gx + gy * gy);
}

/* The two grids of a region between terrain and an upper surface: the same nodes, and the terrain
 * defined at every one. */
static int region_grids_match(const lahar_heightmap *bot, const lahar_heightmap *top, const char *top_path,
                              char *err, size_t errlen)
{
    const double tol = 1e-9 * (bot->cellsize + fabs(bot->x0) + fabs(bot->y0));
    if (top->ncols != bot->ncols || top->nrows != bot->nrows || fabs(top->cellsize - bot->cellsize) > tol ||
        fabs(top->x0 - bot->x0) > tol || fabs(top->y0 - bot->y0) > tol) {
        lahar_errf(err, errlen, "%s: the grid (ncols %d, nrows %d, cellsize %g, first node at %g, %g) is not the "
                 "terrain's (%d, %d, %g, %g, %g); write the upper surface on the terrain's grid", top_path,
                 top->ncols, top->nrows, top->cellsize, top->x0, top->y0, bot->ncols, bot->nrows, bot->cellsize,
                 bot->x0, bot->y0);
        return -1;
    }
    for (int i = 0; i < bot->nrows; i++)
        for (int j = 0; j < bot->ncols; j++)
            if (!lahar_heightmap_valid(bot, i, j)) {
                lahar_errf(err, errlen, "%s: the terrain has no data at row %d from the north, column %d, inside the "
                         "grid of the region; a region between terrain and a surface needs the terrain everywhere "
                         "on the grid", top_path, bot->nrows - i, j + 1);
                return -1;
            }
    return 0;
}

/* The region is empty where the top is on (or below) the raised terrain: the mesh covers only the
 * nodes' window [w[0], w[1]] (rows) x [w[2], w[3]] (columns) around the nodes with the top above
 * it (one node more on each side, for the cells that taper to zero), so the lattice that fills it
 * spans the region, not the whole grid (a small mass on a large terrain: the block's bounding box,
 * and with it the lattice points tested against the mesh, scale with the mass). */
static int region_window(const lahar_heightmap *bot, const lahar_heightmap *top, const char *top_path, double lift,
                         int w[4], char *err, size_t errlen)
{
    int r0 = bot->nrows, r1 = -1, c0 = bot->ncols, c1 = -1;
    for (int i = 0; i < bot->nrows; i++)
        for (int j = 0; j < bot->ncols; j++) {
            int k = i * bot->ncols + j;
            double zb = bot->z[k] + lift * grid_slope_factor(bot, i, j);
            if (lahar_heightmap_valid(top, i, j) && top->z[k] > zb) {
                r0 = i < r0 ? i : r0, r1 = i > r1 ? i : r1;
                c0 = j < c0 ? j : c0, c1 = j > c1 ? j : c1;
            }
        }
    if (r1 < 0) {
        lahar_errf(err, errlen, "%s: the upper surface is nowhere above the terrain; the region is empty", top_path);
        return -1;
    }
    r0 = r0 > 0 ? r0 - 1 : 0, c0 = c0 > 0 ? c0 - 1 : 0;
    r1 = r1 + 1 < bot->nrows ? r1 + 1 : r1, c1 = c1 + 1 < bot->ncols ? c1 + 1 : c1;
    if (r1 == r0 && r1 < bot->nrows - 1) /* a one-row grid cannot hold a region (below) */
        r1++;
    else if (r1 == r0)
        r0--;
    if (c1 == c0 && c1 < bot->ncols - 1)
        c1++;
    else if (c1 == c0)
        c0--;
    if (r0 < 0 || c0 < 0) {
        lahar_errf(err, errlen, "%s: the grid needs at least 2 x 2 nodes for a region", top_path);
        return -1;
    }
    w[0] = r0, w[1] = r1, w[2] = c0, w[3] = c1;
    return 0;
}

/* The closed mesh of the window: nc x nr nodes (local node k = (i - r0) * nc + (j - c0)) on the
 * raised terrain (vertices 0 .. N-1) and on the top (N .. 2N-1, at least the terrain), two
 * triangles per cell on each surface and two per boundary edge on the side walls. */
static void region_mesh(const lahar_heightmap *bot, const lahar_heightmap *top, double lift, const int w[4],
                        lahar_particle_block *pb)
{
    const int r0 = w[0], r1 = w[1], c0 = w[2], c1 = w[3];
    const int nc = c1 - c0 + 1, nr = r1 - r0 + 1, N = nc * nr, nbound = 2 * (nc - 1) + 2 * (nr - 1);
    for (int i = r0; i <= r1; i++)
        for (int j = c0; j <= c1; j++) {
            int g = i * bot->ncols + j, k = (i - r0) * nc + (j - c0);
            double zb = bot->z[g] + lift * grid_slope_factor(bot, i, j);
            double zt = lahar_heightmap_valid(top, i, j) ? top->z[g] : zb;
            if (!(zt > zb))
                zt = zb;
            double x = bot->x0 + j * bot->cellsize, y = bot->y0 + i * bot->cellsize;
            pb->vert[k][0] = pb->vert[N + k][0] = x;
            pb->vert[k][1] = pb->vert[N + k][1] = y;
            pb->vert[k][2] = zb;
            pb->vert[N + k][2] = zt;
        }
    int t = 0;
    for (int i = 0; i + 1 < nr; i++)
        for (int j = 0; j + 1 < nc; j++) {
            int a = i * nc + j, b = a + 1, c = a + nc + 1, d = a + nc;
            int q[4][3] = {{N + a, N + b, N + c}, {N + a, N + c, N + d}, {a, c, b}, {a, d, c}};
            memcpy(pb->tri[t], q, sizeof q);
            t += 4;
        }
    /* side walls: walk the boundary nodes once around */
    int prev = -1;
    for (int s = 0; s <= nbound; s++) {
        int k, m = s % nbound;
        if (m < nc - 1)
            k = m; /* south row, west to east */
        else if (m < nc - 1 + nr - 1)
            k = (m - (nc - 1)) * nc + nc - 1; /* east column, south to north */
        else if (m < 2 * (nc - 1) + nr - 1)
            k = (nr - 1) * nc + (nc - 1 - (m - (nc - 1) - (nr - 1))); /* north row, east to west */
        else
            k = (nr - 1 - (m - 2 * (nc - 1) - (nr - 1))) * nc; /* west column, north to south */
        if (prev >= 0) {
            int q[2][3] = {{prev, k, N + k}, {prev, N + k, N + prev}};
            memcpy(pb->tri[t], q, sizeof q);
            t += 2;
        }
        prev = k;
    }
    pb->kind = LAHAR_BLOCK_MESH;
    pb->nvert = 2 * N;
    pb->ntri = t;
}

int lahar_heightmap_block(const lahar_heightmap *bot, const lahar_heightmap *top, const char *top_path, double lift,
                          lahar_particle_block *pb, char *err, size_t errlen)
{
    int w[4];
    if (region_grids_match(bot, top, top_path, err, errlen) != 0 ||
        region_window(bot, top, top_path, lift, w, err, errlen) != 0)
        return -1;
    const int nc = w[3] - w[2] + 1, nr = w[1] - w[0] + 1, N = nc * nr, nbound = 2 * (nc - 1) + 2 * (nr - 1);
    const int ntri = 4 * (nc - 1) * (nr - 1) + 2 * nbound;
    pb->vert = malloc((size_t)2 * N * sizeof *pb->vert);
    pb->tri = malloc((size_t)ntri * sizeof *pb->tri);
    if (!pb->vert || !pb->tri) {
        free(pb->vert), free(pb->tri);
        pb->vert = NULL, pb->tri = NULL;
        lahar_errf(err, errlen, "out of memory for the region");
        return -1;
    }
    region_mesh(bot, top, lift, w, pb);
    lahar_particle_block_bounds(pb, 3);
    return 0;
}

/* --- 2D profiles -------------------------------------------------------------------------------- */

int lahar_profile_read_csv(const char *path, double (**p)[3], int *n, char *err, size_t errlen)
{
    *p = NULL;
    *n = 0;
    FILE *fp = lahar_fopen_input(path, "r");
    if (!fp) {
        lahar_errf(err, errlen, "%s: cannot open the profile file: %s; check the path", path, strerror(errno));
        return -1;
    }
    char line[4096];
    int ln = 0, cap = 0, header_ok = 1;
    double(*pts)[3] = NULL;
    while (fgets(line, sizeof line, fp)) {
        ln++;
        if (!strchr(line, '\n') && !feof(fp)) {
            lahar_errf(err, errlen, "%s:%d: line longer than %d characters; one point x,y per line", path, ln,
                     (int)sizeof line - 2);
            goto fail;
        }
        line[strcspn(line, "\r\n")] = '\0';
        char *s = line;
        while (isspace((unsigned char)*s))
            s++;
        if (*s == '\0' || *s == '#')
            continue;
        for (char *c = s; *c; c++)
            if (*c == ',' || *c == ';' || *c == '\t')
                *c = ' ';
        double x, y;
        char *end;
        errno = 0;
        x = strtod(s, &end);
        int ok = end != s;
        char *s2 = end;
        y = ok ? strtod(s2, &end) : 0.0;
        ok = ok && end != s2 && errno != ERANGE && isfinite(x) && isfinite(y);
        while (ok && isspace((unsigned char)*end))
            end++;
        if (ok && *end != '\0' && *end != '#') {
            lahar_errf(err, errlen, "%s:%d: more than two values ('%s'); one point x,y per line", path, ln, end);
            goto fail;
        }
        if (!ok) {
            if (header_ok && *n == 0) { /* one header line of column names */
                header_ok = 0;
                continue;
            }
            lahar_errf(err, errlen, "%s:%d: expected two numbers x,y (m); got '%.60s'", path, ln, s);
            goto fail;
        }
        header_ok = 0;
        if (*n == cap) {
            cap = cap ? 2 * cap : 64;
            void *q = realloc(pts, (size_t)cap * sizeof *pts);
            if (!q) {
                lahar_errf(err, errlen, "%s:%d: out of memory", path, ln);
                goto fail;
            }
            pts = q;
        }
        pts[*n][0] = x, pts[*n][1] = y, pts[*n][2] = 0.0;
        ++*n;
    }
    if (ferror(fp)) {
        lahar_errf(err, errlen, "%s: cannot read the file", path);
        goto fail;
    }
    if (*n < 2) {
        lahar_errf(err, errlen, "%s:%d: the profile has %d point(s); it needs at least 2 (x,y per line)", path, ln, *n);
        goto fail;
    }
    fclose(fp);
    *p = pts;
    return 0;
fail:
    fclose(fp);
    free(pts);
    *n = 0;
    return -1;
}

double lahar_profile_height(const double (*p)[3], int n, double x)
{
    if (x <= p[0][0])
        return p[0][1];
    for (int i = 1; i < n; i++)
        if (x <= p[i][0]) {
            double s = (x - p[i - 1][0]) / (p[i][0] - p[i - 1][0]);
            return p[i - 1][1] + s * (p[i][1] - p[i - 1][1]);
        }
    return p[n - 1][1];
}

static void poly_push(double (*out)[3], int *m, double x, double y)
{
    const double eps = 1e-12 * (1.0 + fabs(x) + fabs(y));
    if (*m > 0 && fabs(out[*m - 1][0] - x) <= eps && fabs(out[*m - 1][1] - y) <= eps)
        return;
    out[*m][0] = x, out[*m][1] = y, out[*m][2] = 0.0;
    ++*m;
}

/* The ground raised by `lift` normal to each segment: segment i's line moved up by
 * lift sqrt(1 + slope_i^2) (vertically), evaluated at x. */
static double lifted_line(const double (*g)[3], int i, double lift, double x)
{
    const double sl = (g[i + 1][1] - g[i][1]) / (g[i + 1][0] - g[i][0]);
    return g[i][1] + sl * (x - g[i][0]) + lift * sqrt(1.0 + sl * sl);
}

/* The raised ground at x: the largest of the raised lines of the segments whose x range, widened
 * by lift, holds x (at a vertex the two neighbours meet at their intersection). */
static double lifted_ground(const double (*g)[3], int ng, double lift, double x)
{
    double y = -INFINITY;
    for (int i = 0; i + 1 < ng; i++)
        if (x >= g[i][0] - lift && x <= g[i + 1][0] + lift)
            y = fmax(y, lifted_line(g, i, lift, x));
    return y > -INFINITY ? y : lahar_profile_height(g, ng, x);
}

int lahar_profile_between(const double (*g)[3], int ng, const double (*t)[3], int nt, double lift,
                          double (**poly)[3], int *np, char *err, size_t errlen)
{
    *poly = NULL;
    *np = 0;
    for (int i = 1; i < ng; i++)
        if (!(g[i][0] > g[i - 1][0])) {
            lahar_errf(err, errlen, "the terrain's x must increase from point to point for a region between it and a "
                     "profile (point %d: x = %g after %g)", i, g[i][0], g[i - 1][0]);
            return -1;
        }
    for (int i = 1; i < nt; i++)
        if (!(t[i][0] > t[i - 1][0])) {
            lahar_errf(err, errlen, "the profile's x must increase from point to point (point %d: x = %g after %g)", i,
                     t[i][0], t[i - 1][0]);
            return -1;
        }
    if (t[0][0] < g[0][0] || t[nt - 1][0] > g[ng - 1][0]) {
        lahar_errf(err, errlen, "the profile spans x = %g .. %g, beyond the terrain's %g .. %g; keep it above the "
                 "terrain", t[0][0], t[nt - 1][0], g[0][0], g[ng - 1][0]);
        return -1;
    }
    /* the lower boundary: the raised ground at the profile's points, at the intersections of
     * consecutive raised segments (the raised vertices), sorted by x */
    double(*low)[3] = malloc(((size_t)nt + ng + 2) * sizeof *low);
    double(*out)[3] = malloc(((size_t)2 * nt + 2 * ng + 4) * sizeof *out);
    if (!low || !out) {
        free(low), free(out);
        lahar_errf(err, errlen, "out of memory");
        return -1;
    }
    const double xl = t[0][0], xr = t[nt - 1][0];
    int nl = 0;
    for (int i = 1; i + 1 < ng; i++) {
        /* where the raised lines of segments i - 1 and i cross (the vertex itself when lift = 0) */
        double s0 = (g[i][1] - g[i - 1][1]) / (g[i][0] - g[i - 1][0]), s1 = (g[i + 1][1] - g[i][1]) / (g[i + 1][0] - g[i][0]);
        double xv = g[i][0];
        if (fabs(s1 - s0) > 1e-12)
            xv = g[i][0] + lift * (sqrt(1.0 + s0 * s0) - sqrt(1.0 + s1 * s1)) / (s1 - s0);
        if (xv > xl && xv < xr) {
            low[nl][0] = xv, low[nl][1] = lifted_ground(g, ng, lift, xv), low[nl][2] = 0.0;
            nl++;
        }
    }
    int m = 0, above = 0;
    for (int i = 0; i < nt; i++) {
        double yg = lifted_ground(g, ng, lift, t[i][0]);
        if (t[i][1] > yg)
            above = 1;
        poly_push(out, &m, t[i][0], fmax(t[i][1], yg));
    }
    poly_push(out, &m, xr, lifted_ground(g, ng, lift, xr));
    for (int i = nl - 1; i >= 0; i--)
        poly_push(out, &m, low[i][0], low[i][1]);
    poly_push(out, &m, xl, lifted_ground(g, ng, lift, xl));
    free(low);
    if (m > 1 && fabs(out[m - 1][0] - out[0][0]) <= 1e-12 * (1 + fabs(out[0][0])) &&
        fabs(out[m - 1][1] - out[0][1]) <= 1e-12 * (1 + fabs(out[0][1])))
        m--;
    if (!above || m < 3) {
        free(out);
        lahar_errf(err, errlen, "the profile is nowhere above the terrain%s; the region between them is empty",
                 lift > 0 ? " (its surface and the particles' clearance dx/2)" : "");
        return -1;
    }
    *poly = out;
    *np = m;
    return 0;
}
