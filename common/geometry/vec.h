/* Small vector and quaternion helpers used everywhere (one place for vector math).
 * Header-only so the hot loops inline them. Quaternions are (w, x, y, z), unit length. */
#ifndef LAHAR_VEC_H
#define LAHAR_VEC_H
#include <math.h>

typedef struct { double x, y, z; } vec3;
typedef struct { double w, x, y, z; } quat;

static inline vec3 v3(double x, double y, double z) { vec3 r = {x, y, z}; return r; }
static inline vec3 v3_load(const double a[3]) { return v3(a[0], a[1], a[2]); }
static inline void v3_store(vec3 a, double out[3]) { out[0] = a.x; out[1] = a.y; out[2] = a.z; }
static inline vec3 v3_add(vec3 a, vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline vec3 v3_sub(vec3 a, vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline vec3 v3_scale(vec3 a, double s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline vec3 v3_axpy(double s, vec3 a, vec3 b) { return v3(s * a.x + b.x, s * a.y + b.y, s * a.z + b.z); }
static inline vec3 v3_neg(vec3 a) { return v3(-a.x, -a.y, -a.z); }
static inline double v3_dot(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline vec3 v3_cross(vec3 a, vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double v3_norm2(vec3 a) { return v3_dot(a, a); }
static inline double v3_norm(vec3 a) { return sqrt(v3_dot(a, a)); }
static inline vec3 v3_normalize(vec3 a)
{
    double n = v3_norm(a);
    return n > 0.0 ? v3_scale(a, 1.0 / n) : v3(0.0, 0.0, 0.0);
}
static inline vec3 v3_mul(vec3 a, vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline double v3_get(vec3 a, int i) { return i == 0 ? a.x : (i == 1 ? a.y : a.z); }

static inline quat q_identity(void) { quat q = {1.0, 0.0, 0.0, 0.0}; return q; }
static inline quat q_load(const double a[4]) { quat q = {a[0], a[1], a[2], a[3]}; return q; }
static inline void q_store(quat q, double out[4]) { out[0] = q.w; out[1] = q.x; out[2] = q.y; out[3] = q.z; }
static inline quat q_mul(quat a, quat b)
{
    quat r = {a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
              a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
              a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
              a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
    return r;
}
static inline quat q_conj(quat a) { quat r = {a.w, -a.x, -a.y, -a.z}; return r; }
static inline quat q_normalize(quat a)
{
    double n = sqrt(a.w * a.w + a.x * a.x + a.y * a.y + a.z * a.z);
    quat r = {a.w / n, a.x / n, a.y / n, a.z / n};
    return r;
}
/* Rotation by angle about a unit axis. */
static inline quat q_axis_angle(vec3 unit_axis, double angle)
{
    double s = sin(0.5 * angle);
    quat r = {cos(0.5 * angle), unit_axis.x * s, unit_axis.y * s, unit_axis.z * s};
    return r;
}
/* Rotation by the angle 2 a |u| about u (a >= 0, u != 0): exp(a u) = (cos phi, u a sin(phi)/phi),
 * phi = a |u|. Small angles (phi <= 0.01) by the Taylor series of cos and sin(phi)/phi to phi^6
 * (truncation < 3e-21, below the last bit): no square root, division or sin/cos call; larger ones
 * through q_axis_angle. */
static inline quat q_exp_scaled(vec3 u, double a)
{
    double p2 = (u.x * u.x + u.y * u.y + u.z * u.z) * (a * a);
    if (p2 <= 1e-4) {
        double c = 1.0 + p2 * (-1.0 / 2.0 + p2 * (1.0 / 24.0 + p2 * (-1.0 / 720.0)));
        double s = a * (1.0 + p2 * (-1.0 / 6.0 + p2 * (1.0 / 120.0 + p2 * (-1.0 / 5040.0))));
        quat r = {c, u.x * s, u.y * s, u.z * s};
        return r;
    }
    double un = sqrt(u.x * u.x + u.y * u.y + u.z * u.z);
    vec3 axis = {u.x / un, u.y / un, u.z / un};
    return q_axis_angle(axis, 2.0 * a * un);
}
/* q back to unit length: when |q|^2 is within 1e-8 of 1 (a product of unit quaternions) one Newton
 * step for 1/|q| (relative error ~ (|q|^2 - 1)^2, below the last bit), no square root or division;
 * else q_normalize. */
static inline quat q_renormalize(quat a)
{
    double n2 = a.w * a.w + a.x * a.x + a.y * a.y + a.z * a.z;
    if (!(fabs(n2 - 1.0) <= 1e-8)) return q_normalize(a);
    double f = 1.5 - 0.5 * n2;
    quat r = {a.w * f, a.x * f, a.y * f, a.z * f};
    return r;
}
/* Body frame -> world frame: q v q*. */
static inline vec3 q_rotate(quat q, vec3 v)
{
    vec3 u = v3(q.x, q.y, q.z);
    vec3 t = v3_scale(v3_cross(u, v), 2.0);
    return v3_add(v3_add(v, v3_scale(t, q.w)), v3_cross(u, t));
}
/* World frame -> body frame: q* v q. */
static inline vec3 q_rotate_inv(quat q, vec3 v) { return q_rotate(q_conj(q), v); }
/* Quaternion of a proper rotation matrix m (row-major, m v rotates v); Shepperd's method picks
 * the largest of w, x, y, z to divide by, so it stays accurate for every angle. */
static inline quat q_from_rotmat(const double m[3][3])
{
    double tr = m[0][0] + m[1][1] + m[2][2];
    quat q;
    if (tr > 0.0) {
        double s = 2.0 * sqrt(1.0 + tr);
        q.w = 0.25 * s; q.x = (m[2][1] - m[1][2]) / s; q.y = (m[0][2] - m[2][0]) / s; q.z = (m[1][0] - m[0][1]) / s;
    } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
        double s = 2.0 * sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]);
        q.w = (m[2][1] - m[1][2]) / s; q.x = 0.25 * s; q.y = (m[0][1] + m[1][0]) / s; q.z = (m[0][2] + m[2][0]) / s;
    } else if (m[1][1] > m[2][2]) {
        double s = 2.0 * sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]);
        q.w = (m[0][2] - m[2][0]) / s; q.x = (m[0][1] + m[1][0]) / s; q.y = 0.25 * s; q.z = (m[1][2] + m[2][1]) / s;
    } else {
        double s = 2.0 * sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]);
        q.w = (m[1][0] - m[0][1]) / s; q.x = (m[0][2] + m[2][0]) / s; q.y = (m[1][2] + m[2][1]) / s; q.z = 0.25 * s;
    }
    if (q.w < 0.0) { q.w = -q.w; q.x = -q.x; q.y = -q.y; q.z = -q.z; } /* one canonical sign */
    return q_normalize(q);
}
/* Rotation matrix (row-major) of a unit quaternion. */
static inline void q_to_rotmat(quat q, double m[3][3])
{
    m[0][0] = 1 - 2 * (q.y * q.y + q.z * q.z); m[0][1] = 2 * (q.x * q.y - q.w * q.z); m[0][2] = 2 * (q.x * q.z + q.w * q.y);
    m[1][0] = 2 * (q.x * q.y + q.w * q.z); m[1][1] = 1 - 2 * (q.x * q.x + q.z * q.z); m[1][2] = 2 * (q.y * q.z - q.w * q.x);
    m[2][0] = 2 * (q.x * q.z - q.w * q.y); m[2][1] = 2 * (q.y * q.z + q.w * q.x); m[2][2] = 1 - 2 * (q.x * q.x + q.y * q.y);
}

#endif
