#pragma once
// Eigen-decomposition of a small symmetric matrix by cyclic Jacobi
// rotations: A = V diag(lambda) V^T, columns of V the eigenvectors.
// Device-safe (no allocation, fixed sweep limit); used by the artificial
// stress to work in each particle's principal frame. Checked against
// Eigen's SelfAdjointEigenSolver in the unit tests.
#include <cmath>

#include "rubble/core/hd.hpp"
#include "rubble/core/mat.hpp"

namespace rubble {

template <int D>
struct SymmetricEigen {
  Real lambda[D];
  Mat<D> V;
};

template <int D>
RUBBLE_HD_INLINE SymmetricEigen<D> symmetric_eigen(Mat<D> A) {
  SymmetricEigen<D> out;
  out.V = Mat<D>::identity();
  for (int sweep = 0; sweep < 32; ++sweep) {
    Real off = 0, scale = 0;
    for (int p = 0; p < D; ++p)
      for (int q = 0; q < D; ++q) {
        if (p != q) off += A.m[p][q] * A.m[p][q];
        scale += A.m[p][q] * A.m[p][q];
      }
    if (off <= Real(1e-30) * scale || off == Real(0)) break;
    for (int p = 0; p < D - 1; ++p)
      for (int q = p + 1; q < D; ++q) {
        if (A.m[p][q] == Real(0)) continue;
        // rotation angle that zeroes A_pq (Golub & Van Loan, Alg. 8.4.1)
        const Real theta = (A.m[q][q] - A.m[p][p]) / (Real(2) * A.m[p][q]);
        const Real t = (theta >= 0 ? Real(1) : Real(-1)) / (std::fabs(theta) + std::sqrt(theta * theta + Real(1)));
        const Real c = Real(1) / std::sqrt(t * t + Real(1)), s = t * c;
        for (int k = 0; k < D; ++k) {  // A <- A J
          const Real akp = A.m[k][p], akq = A.m[k][q];
          A.m[k][p] = c * akp - s * akq;
          A.m[k][q] = s * akp + c * akq;
        }
        for (int k = 0; k < D; ++k) {  // A <- J^T A
          const Real apk = A.m[p][k], aqk = A.m[q][k];
          A.m[p][k] = c * apk - s * aqk;
          A.m[q][k] = s * apk + c * aqk;
        }
        for (int k = 0; k < D; ++k) {  // V <- V J
          const Real vkp = out.V.m[k][p], vkq = out.V.m[k][q];
          out.V.m[k][p] = c * vkp - s * vkq;
          out.V.m[k][q] = s * vkp + c * vkq;
        }
      }
  }
  for (int i = 0; i < D; ++i) out.lambda[i] = A.m[i][i];
  return out;
}

}  // namespace rubble
