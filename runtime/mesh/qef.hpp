// The quadratic error function of dual contouring: the point nearest, in the least-squares
// sense, to the tangent planes (p_i, n_i) of a cell's surface crossings. Solved around the
// crossings' mean with a truncated pseudo-inverse (eigenvalues below a tenth of the largest
// dropped): on a flat patch the point stays at the mean; on an edge it lies on the crease;
// at a corner, at the corner.
#pragma once
#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>

namespace sdfc::mesh {

struct Qef {
    double a[6] = {0, 0, 0, 0, 0, 0};  // A = sum n n^T: xx, xy, xz, yy, yz, zz
    double b[3] = {0, 0, 0};           // sum n (n . p)
    glm::dvec3 mass{0.0};
    int count = 0;

    void add(const glm::vec3& p, const glm::vec3& n) {
        const glm::dvec3 dn(n), dp(p);
        const double d = glm::dot(dn, dp);
        a[0] += dn.x * dn.x, a[1] += dn.x * dn.y, a[2] += dn.x * dn.z;
        a[3] += dn.y * dn.y, a[4] += dn.y * dn.z, a[5] += dn.z * dn.z;
        b[0] += dn.x * d, b[1] += dn.y * d, b[2] += dn.z * d;
        mass += dp;
        ++count;
    }

    // The minimiser, or the mean of the crossings where the planes do not pin it down.
    glm::dvec3 solve() const {
        const glm::dvec3 m = count ? mass / double(count) : glm::dvec3(0.0);
        double A[3][3] = {{a[0], a[1], a[2]}, {a[1], a[3], a[4]}, {a[2], a[4], a[5]}};
        // r = b - A m: solve A y = r, x = m + y.
        double r[3];
        for (int i = 0; i < 3; ++i) r[i] = b[i] - (A[i][0] * m.x + A[i][1] * m.y + A[i][2] * m.z);
        // Jacobi eigen-decomposition A = V diag(w) V^T.
        double V[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
        for (int sweep = 0; sweep < 12; ++sweep) {
            const double off = A[0][1] * A[0][1] + A[0][2] * A[0][2] + A[1][2] * A[1][2];
            if (off < 1e-24) break;
            for (int p = 0; p < 2; ++p)
                for (int q = p + 1; q < 3; ++q) {
                    if (std::fabs(A[p][q]) < 1e-30) continue;
                    const double theta = (A[q][q] - A[p][p]) / (2.0 * A[p][q]);
                    const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
                    const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
                    for (int k = 0; k < 3; ++k) {  // A = J^T A J
                        const double akp = A[k][p], akq = A[k][q];
                        A[k][p] = c * akp - s * akq;
                        A[k][q] = s * akp + c * akq;
                    }
                    for (int k = 0; k < 3; ++k) {
                        const double apk = A[p][k], aqk = A[q][k];
                        A[p][k] = c * apk - s * aqk;
                        A[q][k] = s * apk + c * aqk;
                    }
                    for (int k = 0; k < 3; ++k) {
                        const double vkp = V[k][p], vkq = V[k][q];
                        V[k][p] = c * vkp - s * vkq;
                        V[k][q] = s * vkp + c * vkq;
                    }
                }
        }
        const double wmax = std::max({std::fabs(A[0][0]), std::fabs(A[1][1]), std::fabs(A[2][2])});
        glm::dvec3 y(0.0);
        for (int i = 0; i < 3; ++i) {
            const double w = A[i][i];
            if (!(std::fabs(w) > 0.1 * wmax) || w == 0.0) continue;
            const double proj = (V[0][i] * r[0] + V[1][i] * r[1] + V[2][i] * r[2]) / w;
            y += proj * glm::dvec3(V[0][i], V[1][i], V[2][i]);
        }
        return m + y;
    }
};

}  // namespace sdfc::mesh
