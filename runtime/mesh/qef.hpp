// The quadratic error function of dual contouring: the point nearest, in the least-squares
// sense, to the tangent planes (p_i, n_i) of a cell's surface crossings. Solved around the
// crossings' mean with a truncated pseudo-inverse (eigenvalues below a tenth of the largest
// dropped): on a flat patch the point stays at the mean; on an edge it lies on the crease;
// at a corner, at the corner; within a box when asked (solve_in). The simplifier
// (simplify.cpp) merges vertices' QEFs, made of their triangles' planes, and asks their error.
#pragma once
#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace sdfc::mesh {

struct Qef {
    double a[6] = {0, 0, 0, 0, 0, 0};  // A = sum n n^T: xx, xy, xz, yy, yz, zz
    double b[3] = {0, 0, 0};           // sum n (n . p)
    double c = 0.0;                    // sum (n . p)^2
    glm::dvec3 mass{0.0};              // sum p
    double weight = 0.0;               // of the planes: their count, or the triangles' areas

    void add(const glm::vec3& p, const glm::vec3& n, double w = 1.0) {
        const glm::dvec3 dn(n), dp(p);
        const double d = glm::dot(dn, dp);
        a[0] += w * dn.x * dn.x, a[1] += w * dn.x * dn.y, a[2] += w * dn.x * dn.z;
        a[3] += w * dn.y * dn.y, a[4] += w * dn.y * dn.z, a[5] += w * dn.z * dn.z;
        b[0] += w * dn.x * d, b[1] += w * dn.y * d, b[2] += w * dn.z * d;
        c += w * d * d;
        mass += w * dp;
        weight += w;
    }

    void merge(const Qef& o) {
        for (int i = 0; i < 6; ++i) a[i] += o.a[i];
        for (int i = 0; i < 3; ++i) b[i] += o.b[i];
        c += o.c, mass += o.mass, weight += o.weight;
    }

    // The weighted sum of the squared distances from x to the planes.
    double error(const glm::dvec3& x) const {
        const double ax = a[0] * x.x + a[1] * x.y + a[2] * x.z;
        const double ay = a[1] * x.x + a[3] * x.y + a[4] * x.z;
        const double az = a[2] * x.x + a[4] * x.y + a[5] * x.z;
        return std::max(0.0, x.x * ax + x.y * ay + x.z * az - 2.0 * (b[0] * x.x + b[1] * x.y + b[2] * x.z) + c);
    }

    // The minimiser, or the mean of the crossings where the planes do not pin it down.
    glm::dvec3 solve() const {
        const bool none[3] = {false, false, false};
        return solve_with(none, glm::dvec3(0.0));
    }

    // The minimiser within the box [lo, hi] (a vertex must stay in its cell): where the free
    // minimiser leaves the box, the coordinates it leaves by are fixed on the box's side and
    // the others solved again (a few rounds: the point on the cell's face or edge nearest to
    // the planes), rather than clamped, which would move it off the surface.
    glm::dvec3 solve_in(const glm::dvec3& lo, const glm::dvec3& hi) const {
        bool fixed[3] = {false, false, false};
        glm::dvec3 at(0.0), x = solve();
        for (int round = 0; round < 3; ++round) {
            bool moved = false;
            for (int i = 0; i < 3; ++i) {
                if (fixed[i] || (x[i] >= lo[i] && x[i] <= hi[i])) continue;
                fixed[i] = true, at[i] = x[i] < lo[i] ? lo[i] : hi[i], moved = true;
            }
            if (!moved) break;
            x = solve_with(fixed, at);
        }
        return glm::clamp(x, lo, hi);
    }

private:
    // Minimises with the coordinates marked `fixed` held at `at`.
    glm::dvec3 solve_with(const bool fixed[3], const glm::dvec3& at) const {
        glm::dvec3 m = weight > 0.0 ? mass / weight : glm::dvec3(0.0);
        for (int i = 0; i < 3; ++i)
            if (fixed[i]) m[i] = at[i];
        const double full[3][3] = {{a[0], a[1], a[2]}, {a[1], a[3], a[4]}, {a[2], a[4], a[5]}};
        // The free coordinates' system around m: A_uu y = b_u - (A m)_u.
        int free_axes[3], n = 0;
        for (int i = 0; i < 3; ++i)
            if (!fixed[i]) free_axes[n++] = i;
        double A[3][3] = {}, r[3] = {};
        for (int i = 0; i < n; ++i) {
            const int u = free_axes[i];
            r[i] = b[u] - (full[u][0] * m.x + full[u][1] * m.y + full[u][2] * m.z);
            for (int j = 0; j < n; ++j) A[i][j] = full[u][free_axes[j]];
        }
        double y[3] = {0, 0, 0};
        pseudo_solve(A, r, n, y);
        for (int i = 0; i < n; ++i) m[free_axes[i]] += y[i];
        return m;
    }

    // y = A^+ r for symmetric n x n A (n <= 3): Jacobi eigen-decomposition, eigenvalues
    // below a tenth of the largest dropped.
    static void pseudo_solve(double A[3][3], const double r[3], int n, double y[3]) {
        double V[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        for (int sweep = 0; sweep < 12; ++sweep) {
            double off = 0.0;
            for (int p = 0; p < n; ++p)
                for (int q = p + 1; q < n; ++q) off += A[p][q] * A[p][q];
            if (off < 1e-24) break;
            for (int p = 0; p < n; ++p)
                for (int q = p + 1; q < n; ++q) {
                    if (std::fabs(A[p][q]) < 1e-30) continue;
                    const double theta = (A[q][q] - A[p][p]) / (2.0 * A[p][q]);
                    const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
                    const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                    for (int k = 0; k < n; ++k) {  // A = J^T A J
                        const double akp = A[k][p], akq = A[k][q];
                        A[k][p] = c * akp - s * akq;
                        A[k][q] = s * akp + c * akq;
                    }
                    for (int k = 0; k < n; ++k) {
                        const double apk = A[p][k], aqk = A[q][k];
                        A[p][k] = c * apk - s * aqk;
                        A[q][k] = s * apk + c * aqk;
                    }
                    for (int k = 0; k < n; ++k) {
                        const double vkp = V[k][p], vkq = V[k][q];
                        V[k][p] = c * vkp - s * vkq;
                        V[k][q] = s * vkp + c * vkq;
                    }
                }
        }
        double wmax = 0.0;
        for (int i = 0; i < n; ++i) wmax = std::max(wmax, std::fabs(A[i][i]));
        for (int i = 0; i < n; ++i) y[i] = 0.0;
        for (int i = 0; i < n; ++i) {
            const double w = A[i][i];
            if (!(std::fabs(w) > 0.1 * wmax) || w == 0.0) continue;
            double proj = 0.0;
            for (int k = 0; k < n; ++k) proj += V[k][i] * r[k];
            proj /= w;
            for (int k = 0; k < n; ++k) y[k] += proj * V[k][i];
        }
    }
};

}  // namespace sdfc::mesh
