/* Kernels (common/kernels/kernel.h) checked numerically on a fine lattice (spacing h/40 in 2D, h/16 in
 * 3D, origin shifted off the kernel centre so that no symmetry hides an error), tolerance 1e-3:
 *   sum W dV = 1                         (normalisation: catches the constants of Trujillo-Vela et al. 2020 eq. 4;
 *                                         the quintic 3D constant is 1/(120 pi), not 3/(359 pi))
 *   sum grad W dV = 0                    (each component)
 *   sum x (x) grad W dV = -I             (trace -D: the gradient of a linear field is exact)
 * and dW/dr against a central difference of W (relative 1e-6), W(r >= kappa h) = 0, continuity at
 * the support edge. Also the table lookup by name. */
#include <math.h>
#include <stdio.h>
#include "kernel.h"

#include "test_util.h"

static void check_kernel(const char *name, int dim)
{
    const double h = 0.7;
    kernel k;
    CHECK(kernel_init(&k, name, dim, h) == 0, "kernel_init(%s, %d)", name, dim);
    const double step = h / (dim == 2 ? 40.0 : 16.0);
    const double shift[3] = {0.31 * step, 0.17 * step, 0.43 * step};
    int n = (int)ceil(k.support / step) + 2;
    double sw = 0.0, sg[3] = {0, 0, 0}, sxg[3][3] = {{0}};
    int nz = dim == 3 ? n : 0;
    for (int a = -n; a <= n; a++)
        for (int b = -n; b <= n; b++)
            for (int c = -nz; c <= nz; c++) {
                double x[3] = {a * step + shift[0], b * step + shift[1], dim == 3 ? c * step + shift[2] : 0.0};
                double r = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
                sw += kernel_w(&k, r);
                if (r > 0.0) {
                    double g = kernel_dwdr(&k, r) / r;
                    for (int i = 0; i < dim; i++) {
                        sg[i] += g * x[i];
                        for (int j = 0; j < dim; j++)
                            sxg[i][j] += x[i] * g * x[j];
                    }
                }
            }
    double dv = pow(step, dim);
    sw *= dv;
    double worst_g = 0.0, worst_xg = 0.0;
    for (int i = 0; i < dim; i++) {
        worst_g = fmax(worst_g, fabs(sg[i] * dv) * h); /* grad W ~ 1/h: scale to O(1) */
        for (int j = 0; j < dim; j++)
            worst_xg = fmax(worst_xg, fabs(sxg[i][j] * dv + (i == j ? 1.0 : 0.0)));
    }
    printf("%-9s %dD: int W = %.6f, |int grad W| h = %.2e, max |int x grad W + I| = %.2e\n", name, dim, sw, worst_g,
           worst_xg);
    CHECK(fabs(sw - 1.0) < 1e-3, "%s %dD: int W dV = %.6f, expected 1", name, dim, sw);
    CHECK(worst_g < 1e-3, "%s %dD: int grad W dV = %.2e, expected 0", name, dim, worst_g);
    CHECK(worst_xg < 1e-3, "%s %dD: int x grad W dV off -I by %.2e", name, dim, worst_xg);

    /* derivative against a central difference, zero outside the support, continuity at the edge */
    double worst_d = 0.0;
    for (double q = 0.05; q < k.support / h - 0.05; q += 0.0371) {
        double r = q * h, e = 1e-6 * h;
        double fd = (kernel_w(&k, r + e) - kernel_w(&k, r - e)) / (2.0 * e);
        worst_d = fmax(worst_d, fabs(fd - kernel_dwdr(&k, r)) / (k.norm / h));
    }
    CHECK(worst_d < 1e-6, "%s %dD: dW/dr off its central difference by %.2e (relative)", name, dim, worst_d);
    CHECK(fabs(kernel_w(&k, k.support)) < 1e-12 * k.norm && kernel_w(&k, 1.5 * k.support) == 0.0 &&
              fabs(kernel_dwdr(&k, k.support)) < 1e-9 * k.dnorm && kernel_dwdr(&k, 1.5 * k.support) == 0.0,
          "%s: W or dW/dr nonzero at/after the support", name);
    CHECK(fabs(kernel_w(&k, k.support * (1 - 1e-6))) < 1e-12 * k.norm, "%s: W discontinuous at the support", name);
}

/* The level gauge's line: one particle's contribution is W at every point within the support and
 * nothing beyond; the crossings of a phi falling linearly from 1 at z = 0 to 0 at z = 1 lie at
 * 1 - frac either way, and the dry and flooded ends give the documented answers. */
static void check_line(void)
{
    kernel k;
    kernel_init(&k, "cubic", 2, 0.013);
    enum { N = 101 };
    double phi[N] = {0}, step = 0.001, z0 = 0.0, zj = 0.05, rh2 = 0.01 * 0.01;
    kernel_line_add(&k, rh2, zj, 2.0, z0, step, N, phi);
    int wrong = 0;
    for (int i = 0; i < N; i++) {
        double dz = z0 + i * step - zj, w = 2.0 * kernel_w(&k, sqrt(rh2 + dz * dz));
        wrong += fabs(phi[i] - w) > 1e-12 * k.norm;
    }
    CHECK(wrong == 0, "kernel_line_add: %d of %d points differ from v W(r)", wrong, N);
    for (int i = 0; i < N; i++)
        phi[i] = 1.0 - (double)i / (N - 1);
    double up = kernel_line_crossing(phi, N, 0.01, 0.5, 0), down = kernel_line_crossing(phi, N, 0.01, 0.5, 1);
    CHECK(fabs(up - 0.5) < 1e-12 && fabs(down - 0.5) < 1e-12, "crossing of a linear phi: up %g, down %g (0.5)", up,
          down);
    up = kernel_line_crossing(phi, N, 0.01, 0.25, 0), down = kernel_line_crossing(phi, N, 0.01, 0.25, 1);
    CHECK(fabs(up - 0.75) < 1e-12 && fabs(down - 0.75) < 1e-12, "crossing at 1/4: up %g, down %g (0.75)", up, down);
    CHECK(kernel_line_crossing(phi, N, 0.01, 1.5, 0) == 0.0 && isnan(kernel_line_crossing(phi, N, 0.01, 1.5, 1)),
          "never wet: 0 going up, NAN coming down");
    CHECK(kernel_line_crossing(phi, N, 0.01, -1.0, 0) == 1.0 && isnan(kernel_line_crossing(phi, N, 0.01, -1.0, 1)),
          "wet to the top: the line's top going up, NAN coming down");
}

int main(void)
{
    check_line();
    const char *names[] = {"cubic", "quintic", "wendland2"};
    for (int i = 0; i < 3; i++)
        for (int dim = 2; dim <= 3; dim++)
            check_kernel(names[i], dim);
    kernel k;
    CHECK(kernel_init(&k, "gaussian", 2, 1.0) == -1, "unknown kernel accepted");
    CHECK(kernel_init(&k, "cubic", 1, 1.0) == -1, "dimension 1 accepted");
    CHECK(kernel_find("quintic") && kernel_find("quintic")->kappa == 3.0, "quintic support");
    CHECK(kernel_def_of(KERNEL_WENDLAND2) == kernel_find("wendland2"), "table order");
    /* the often quoted 3D quintic constant 3/(359 pi) (shared/papers/README.md) is off by 0.28 %: this
     * test resolves 1e-3, so it would fail with that constant; 1/(120 pi) (Trujillo-Vela et al. 2020 eq. 4) is right */
    CHECK(fabs((3.0 / 359.0) / (1.0 / 120.0) - 1.0) > 2e-3, "3/359 and 1/120 indistinguishable at 1e-3");
    if (failures)
        return 1;
    printf("PASS test_kernel\n");
    return 0;
}
