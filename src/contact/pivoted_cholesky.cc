#include "contact/pivoted_cholesky.h"

#include <cmath>
#include <utility>

namespace rigidtouch::contact {

int PivotedCholesky(Eigen::MatrixXd& work, int n, Eigen::VectorXi& order, double threshold) {
  for (int k = 0; k < n; ++k) {
    int q = k;
    for (int i = k + 1; i < n; ++i) {
      if (work(i, i) > work(q, q)) q = i;
    }
    if (!(work(q, q) > threshold)) return k;
    if (q != k) {
      work.row(k).head(n).swap(work.row(q).head(n));
      work.col(k).head(n).swap(work.col(q).head(n));
      std::swap(order[k], order[q]);
    }
    const double l_kk = std::sqrt(work(k, k));
    work(k, k) = l_kk;
    for (int i = k + 1; i < n; ++i) work(i, k) /= l_kk;
    for (int j = k + 1; j < n; ++j) {
      for (int i = j; i < n; ++i) {
        work(i, j) -= work(i, k) * work(j, k);
        work(j, i) = work(i, j);
      }
    }
  }
  return n;
}

}  // namespace rigidtouch::contact
