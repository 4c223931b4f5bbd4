/* SPH smoothing kernels, in one place: W(r, h) = sigma_D / h^D * f(q), q = r / h, compact support
 * kappa h. Three kernels, selectable by name through a table (kernel_find):
 *   "cubic"     cubic spline (Monaghan & Lattanzio 1985), kappa = 2,
 *               sigma 2D 10/(7 pi), 3D 1/pi. This is the f(q) printed in Trujillo-Vela et al. 2020 eq. 4.
 *   "quintic"   quintic spline (Morris et al. 1997), kappa = 3,
 *               sigma 2D 7/(478 pi), 3D 1/(120 pi). Trujillo-Vela et al. 2020, eq. 4, print these constants
 *               beside the cubic f(q): they belong to this kernel (shared/papers/README.md). The
 *               README's 3D value 3/(359 pi) (as in Liu & Liu 2003) integrates to 1.0028, not 1;
 *               1/(120 pi) integrates to 1 within 1e-6 (tests/test_kernel.c).
 *   "wendland2" Wendland C2 (Wendland 1995; Dehnen & Aly 2012 in the q = r/h, support 2h
 *               scaling), kappa = 2, sigma 2D 7/(4 pi), 3D 21/(16 pi).
 * The hot loops call kernel_w / kernel_dwdr, static inline with a switch on the kind, which is
 * loop-invariant: the compiler hoists it, or callers switch once outside the pair loop and pass a
 * constant kind to kernel_shape / kernel_dshape. */
#ifndef LAHAR_KERNEL_H
#define LAHAR_KERNEL_H

typedef enum { KERNEL_CUBIC = 0, KERNEL_QUINTIC = 1, KERNEL_WENDLAND2 = 2, KERNEL_COUNT } kernel_kind;

/* One entry of the kernel table: the dimensionless shape f(q) and df/dq, the support radius in
 * units of h and the normalisation constants. */
typedef struct {
    const char *name;
    kernel_kind kind;
    double kappa;     /* support radius / h */
    double sigma[2];  /* sigma for D = 2, 3: W = sigma / h^D f(q) */
    double (*f)(double q);
    double (*dfdq)(double q);
} kernel_def;

/* A kernel ready for use: kind, dimension and smoothing length folded into constants. */
typedef struct {
    kernel_kind kind;
    int dim;
    double h, inv_h;
    double support;   /* kappa h */
    double norm;      /* sigma_D / h^D */
    double dnorm;     /* sigma_D / h^(D+1) */
} kernel;

/* The table entry called `name` ("cubic", "quintic", "wendland2"), or NULL. */
const kernel_def *kernel_find(const char *name);
/* The table entry of a kind. */
const kernel_def *kernel_def_of(kernel_kind kind);
/* Fill k for kernel `name` in dimension dim (2 or 3) with smoothing length h > 0. Returns 0, or -1
 * for an unknown name, dimension or h <= 0. */
int kernel_init(kernel *k, const char *name, int dim, double h);

/* Dimensionless shapes; q >= 0. */
static inline double kernel_shape(kernel_kind kind, double q)
{
    switch (kind) {
    case KERNEL_CUBIC:
        if (q < 1.0) return 1.0 - 1.5 * q * q + 0.75 * q * q * q;
        if (q < 2.0) { double a = 2.0 - q; return 0.25 * a * a * a; }
        return 0.0;
    case KERNEL_QUINTIC: {
        double w = 0.0, a;
        if (q < 3.0) { a = 3.0 - q; w += a * a * a * a * a; }
        if (q < 2.0) { a = 2.0 - q; w -= 6.0 * a * a * a * a * a; }
        if (q < 1.0) { a = 1.0 - q; w += 15.0 * a * a * a * a * a; }
        return w;
    }
    case KERNEL_WENDLAND2:
        if (q < 2.0) { double a = 1.0 - 0.5 * q; return a * a * a * a * (2.0 * q + 1.0); }
        return 0.0;
    default:
        return 0.0;
    }
}

static inline double kernel_dshape(kernel_kind kind, double q)
{
    switch (kind) {
    case KERNEL_CUBIC:
        if (q < 1.0) return -3.0 * q + 2.25 * q * q;
        if (q < 2.0) { double a = 2.0 - q; return -0.75 * a * a; }
        return 0.0;
    case KERNEL_QUINTIC: {
        double d = 0.0, a;
        if (q < 3.0) { a = 3.0 - q; d -= 5.0 * a * a * a * a; }
        if (q < 2.0) { a = 2.0 - q; d += 30.0 * a * a * a * a; }
        if (q < 1.0) { a = 1.0 - q; d -= 75.0 * a * a * a * a; }
        return d;
    }
    case KERNEL_WENDLAND2:
        if (q < 2.0) { double a = 1.0 - 0.5 * q; return -5.0 * q * a * a * a; }
        return 0.0;
    default:
        return 0.0;
    }
}

/* df/dq divided by q, so that W'(r)/r = dnorm / h * kernel_dshape_over_q(q) needs no division by r
 * in the pair loops (Wendland C2: -5 (1 - q/2)^3; cubic q < 1: -3 + 9/4 q). The limit at q = 0 for
 * the Wendland and cubic kernels, 0 there for the quintic (where df/dq = 0 too). */
static inline double kernel_dshape_over_q(kernel_kind kind, double q)
{
    switch (kind) {
    case KERNEL_CUBIC:
        if (q < 1.0) return -3.0 + 2.25 * q;
        if (q < 2.0) { double a = 2.0 - q; return -0.75 * a * a / q; }
        return 0.0;
    case KERNEL_WENDLAND2:
        if (q < 2.0) { double a = 1.0 - 0.5 * q; return -5.0 * a * a * a; }
        return 0.0;
    default:
        return q > 0.0 ? kernel_dshape(kind, q) / q : 0.0;
    }
}

/* W(r, h). */
static inline double kernel_w(const kernel *k, double r) { return k->norm * kernel_shape(k->kind, r * k->inv_h); }
/* dW/dr (<= 0); grad_i W(x_i - x_j) = dW/dr * (x_i - x_j) / r. */
static inline double kernel_dwdr(const kernel *k, double r) { return k->dnorm * kernel_dshape(k->kind, r * k->inv_h); }

/* ---- the free-surface level along a vertical line (level gauges, `lahar check`'s still-water
 * level): the height where the kernel-summed fluid volume fraction sum_j V_j W(x - x_j) falls to
 * KERNEL_SURFACE_FRACTION. Full support gives 1, a flat free surface cuts the support in half:
 * on a particle lattice the 1/2 crossing lies within 1e-3 dx of the top row + dx/2 (cubic,
 * h = 1.3 dx, 2D and 3D), and it averages over the support: where one surface particle is
 * missing it drops 0.5 dx (a column's top particle: 1 dx), where one is raised dx/2 it rises
 * 0.12 dx (tests/test_check_fluid.c). The rule of the DualSPHysics MeasureTool (kclimit 0.5). */
#define KERNEL_SURFACE_FRACTION 0.5

/* Add v W(r) to phi[i] at the npt points z0 + i step of a vertical line, r the distance from a
 * particle at height zj whose horizontal distance to the line squared is rh2 (only the points
 * within the support are visited). */
void kernel_line_add(const kernel *k, double rh2, double zj, double v, double z0, double step, int npt,
                     double *phi);
/* Where phi (the npt line points z0 + i step) crosses frac, in m above z0, linearly interpolated
 * between points. from_top = 0: the first crossing going up from i = 0 (the top of the water
 * column standing on the line's foot; 0 when phi[0] < frac, the top of the line when phi never
 * falls below frac). from_top = 1: the first point with phi >= frac coming down from the top
 * (the uppermost surface; NAN when phi never reaches frac or the top point is already wet). */
double kernel_line_crossing(const double *phi, int npt, double step, double frac, int from_top);

#endif
