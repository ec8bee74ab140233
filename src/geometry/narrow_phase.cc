#include "geometry/narrow_phase.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace rigidtouch::geometry {
namespace {

// another axis replaces the preferred one only if it penetrates at least 5% less (Box2D's
// relative tolerance): near ties, a resting stack keeps one reference face instead of flipping
constexpr double kAxisRelativeTolerance = 0.95;
// and by more than this, so that barely touching boxes do not flip axes on rounding noise
constexpr double kAxisAbsoluteTolerance_m = 1e-9;
// edge pairs closer to parallel than this (sine of their angle) are covered by the face axes;
// their cross product is too short to normalise reliably
constexpr double kMinEdgeAxisSine = 1e-6;
// an incident corner past a side plane of the reference face by at most this fraction of the
// face's half-extent is moved onto the plane instead of being clipped. What clipping would cut
// off is then a sliver that thin, and the corner stands for the sliver's two vertices. Coincident
// faces of equal boxes (a stack) have half their corners outside by rounding alone (under 1e-15 m
// on the benchmark's settled stack of 25 mm boxes); clipping them cost 40% of the face manifold
constexpr double kCornerTolerance = 1e-9;
// at most this many points per face manifold: 4 span a face, more only cost solver rows
constexpr int kMaxManifoldPoints = 4;
// clipping a quad against 4 half-planes gives at most 8 vertices when convex; the extra room
// absorbs rounding that makes a polygon slightly non-convex
constexpr int kClipBuffer = 16;

// sign that never returns 0, so that ties pick a fixed side
double Sign(double x) {
  return x < 0.0 ? -1.0 : 1.0;
}

// x * 0 is 0 for finite x and NaN for an infinity or NaN, so the sum is 0 only if all are finite
double FiniteTest(const double* x, int n) {
  double sum = 0.0;
  for (int i = 0; i < n; ++i) sum += x[i] * 0.0;
  return sum;
}

// whether every number of the n points is finite: x * 0 is 0 for a finite x and NaN otherwise,
// and the NaN survives every later sum. Summed per coordinate over all points, with one test.
bool PointsFinite(const ContactPoint* c, int n) {
  Vec3 zero = Vec3::Zero();
  double zero_depth = 0.0;
  for (int i = 0; i < n; ++i) {
    zero += c[i].p_W * 0.0 + c[i].n_W * 0.0;
    zero_depth += c[i].depth_m * 0.0;
  }
  return zero.sum() + zero_depth == 0.0;
}

// the other two axes of axis k in cyclic order: (k + 1) % 3 and (k + 2) % 3
constexpr int kNext1[3] = {1, 2, 0};
constexpr int kNext2[3] = {2, 0, 1};

}  // namespace

bool SizeValid(GeomType type, const Vec3& size) {
  switch (type) {
    case GeomType::kPlane:
      return true;
    case GeomType::kSphere:
      return size.x() > 0.0 && size.x() * 0.0 == 0.0;
    case GeomType::kBox:
      return size.x() > 0.0 && size.y() > 0.0 && size.z() > 0.0 &&
             FiniteTest(size.data(), 3) == 0.0;
    default:
      return false;
  }
}

namespace {

// sphere (geom 1) against plane (geom 2): the half-space below the plane is solid
int SpherePlane(const Vec3& c_W, double radius_m, const GeomPose& plane, ContactPoint* out) {
  const Vec3 n_W = plane.R_WG.col(2);
  const double height_m = n_W.dot(c_W - plane.p_W);
  const double depth_m = radius_m - height_m;
  if (!(depth_m > 0.0)) return 0;
  // midpoint of the sphere's lowest point c - r n and its projection c - height n
  out[0] = {c_W - 0.5 * (radius_m + height_m) * n_W, n_W, depth_m};
  return 1;
}

int SphereSphere(const Vec3& c1_W, double r1_m, const Vec3& c2_W, double r2_m, ContactPoint* out) {
  const Vec3 d_W = c1_W - c2_W;
  const double dist_m = d_W.norm();
  const double depth_m = r1_m + r2_m - dist_m;
  if (!(depth_m > 0.0)) return 0;
  // concentric spheres have no preferred direction: a fixed one keeps the result deterministic
  const Vec3 n_W = dist_m > 0.0 ? Vec3(d_W / dist_m) : Vec3::UnitZ();
  out[0] = {0.5 * ((c1_W - r1_m * n_W) + (c2_W + r2_m * n_W)), n_W, depth_m};
  return 1;
}

// sphere (geom 1) against box (geom 2)
int SphereBox(const Vec3& c_W, double radius_m, const GeomPose& box, const Vec3& half_m,
              ContactPoint* out) {
  const Vec3 c_G = box.R_WG.transpose() * (c_W - box.p_W);
  Vec3 q_G = c_G.cwiseMax(-half_m).cwiseMin(half_m);  // closest box point to the centre
  const Vec3 d_G = c_G - q_G;
  const double dist2_m2 = d_G.squaredNorm();
  Vec3 n_G;
  double depth_m = 0.0;
  if (dist2_m2 > 0.0) {
    if (dist2_m2 >= radius_m * radius_m) return 0;
    const double dist_m = std::sqrt(dist2_m2);
    n_G = d_G / dist_m;
    depth_m = radius_m - dist_m;
  } else {
    // centre inside (or on) the box: push out through the nearest face, lowest axis on ties
    int k = 0;
    double gap_m = half_m[0] - std::abs(c_G[0]);
    for (int i = 1; i < 3; ++i) {
      const double g = half_m[i] - std::abs(c_G[i]);
      if (g < gap_m) {
        gap_m = g;
        k = i;
      }
    }
    const double s = Sign(c_G[k]);
    n_G = Vec3::Zero();
    n_G[k] = s;
    q_G[k] = s * half_m[k];
    depth_m = radius_m + gap_m;
  }
  if (!(depth_m > 0.0)) return 0;
  const Vec3 n_W = box.R_WG * n_G;
  const Vec3 q_W = box.p_W + box.R_WG * q_G;
  out[0] = {0.5 * ((c_W - radius_m * n_W) + q_W), n_W, depth_m};
  return 1;
}

// box (geom 1) against plane (geom 2): every vertex below the plane, the deepest `max_points`
// if more penetrate, written in vertex order so that a resting face gives a fixed order
int BoxPlane(const GeomPose& box, const Vec3& half_m, const GeomPose& plane, ContactPoint* out,
             int max_points) {
  const Vec3 n_W = plane.R_WG.col(2);
  const double centre_height_m = n_W.dot(box.p_W - plane.p_W);
  // extent of each box axis along the plane normal
  const Vec3 reach_m = (box.R_WG.transpose() * n_W).cwiseProduct(half_m);
  if (centre_height_m - reach_m.cwiseAbs().sum() >= 0.0) return 0;
  double depth_m[8];
  bool keep[8];
  int count = 0;
  for (int v = 0; v < 8; ++v) {
    // vertex v has sign + on axis k when bit k of v is set
    const double h = centre_height_m + ((v & 1) ? reach_m[0] : -reach_m[0]) +
                     ((v & 2) ? reach_m[1] : -reach_m[1]) + ((v & 4) ? reach_m[2] : -reach_m[2]);
    depth_m[v] = -h;
    keep[v] = h < 0.0;
    if (keep[v]) ++count;
  }
  // only a box deeper than its own thickness has more: drop the shallowest, highest vertex on ties
  while (count > max_points) {
    int drop = -1;
    for (int v = 0; v < 8; ++v) {
      if (keep[v] && (drop < 0 || depth_m[v] <= depth_m[drop])) drop = v;
    }
    keep[drop] = false;
    --count;
  }
  int n = 0;
  for (int v = 0; v < 8; ++v) {
    if (!keep[v]) continue;
    const Vec3 corner_G((v & 1) ? half_m[0] : -half_m[0], (v & 2) ? half_m[1] : -half_m[1],
                        (v & 4) ? half_m[2] : -half_m[2]);
    const Vec3 vertex_W = box.p_W + box.R_WG * corner_G;
    out[n++] = {vertex_W + 0.5 * depth_m[v] * n_W, n_W, depth_m[v]};
  }
  return n;
}

// a polygon in reference-face coordinates: (u, v) along the face's tangent axes, z the height
// above the face (negative below). Stored as separate coordinate arrays so that a clip step's
// distance loop reads only the coordinate it tests.
struct FacePolygon {
  double u[kClipBuffer], v[kClipBuffer], z[kClipBuffer];
  int n = 0;
};

// Sutherland-Hodgman step: keeps the part of polygon `in` with sign * coordinate <= limit, the
// coordinate v if kAlongV else u, the sign -1 if kNegative else +1; vertices exactly on the line
// are kept and create no duplicate. Returns false, leaving `out` untouched, when every vertex is
// kept: then the step would copy `in` unchanged (a crossing needs a vertex past the line), and
// most steps on a resting pair are such copies.
template <bool kAlongV, bool kNegative>
bool ClipPolygon(const FacePolygon& in, double limit, FacePolygon& out) {
  const int n = in.n;
  const double* x = kAlongV ? in.v : in.u;
  // signed distances past the line (multiplying by -1 or 1 is exact: a negation or nothing)
  double f[kClipBuffer];
  bool all_kept = true;
  for (int i = 0; i < n; ++i) {
    f[i] = (kNegative ? -x[i] : x[i]) - limit;
    // written as "kept" rather than "not past" so that a NaN distance still takes the full step,
    // which drops that vertex; & rather than && needs no branch per vertex
    all_kept = all_kept & (f[i] <= 0.0);
  }
  if (all_kept) return false;
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const int next = i + 1 < n ? i + 1 : 0;
    const double fp = f[i];
    const double fq = f[next];
    if (fp <= 0.0 && m < kClipBuffer) {
      out.u[m] = in.u[i];
      out.v[m] = in.v[i];
      out.z[m] = in.z[i];
      ++m;
    }
    if (((fp < 0.0 && fq > 0.0) || (fp > 0.0 && fq < 0.0)) && m < kClipBuffer) {
      const double t = fp / (fp - fq);
      out.u[m] = in.u[i] + t * (in.u[next] - in.u[i]);
      out.v[m] = in.v[i] + t * (in.v[next] - in.v[i]);
      out.z[m] = in.z[i] + t * (in.z[next] - in.z[i]);
      ++m;
    }
  }
  out.n = m;
  return true;
}

// chooses at most `max_points` of the n points of `p`: the deepest, the farthest from it, then
// those that maximise the spanned area; marks them in `keep`. First index wins every tie.
void ReduceManifold(const FacePolygon& p, int max_points, bool* keep) {
  const int n = p.n;
  for (int i = 0; i < n; ++i) keep[i] = false;
  int i0 = 0;
  for (int i = 1; i < n; ++i) {
    if (p.z[i] < p.z[i0]) i0 = i;
  }
  keep[i0] = true;
  if (max_points < 2) return;
  const double u0 = p.u[i0], v0 = p.v[i0];
  int i1 = -1;
  double best = -1.0;
  for (int i = 0; i < n; ++i) {
    const double du = p.u[i] - u0, dv = p.v[i] - v0;
    const double d2 = du * du + dv * dv;
    if (!keep[i] && d2 > best) {
      best = d2;
      i1 = i;
    }
  }
  if (i1 < 0) return;
  keep[i1] = true;
  if (max_points < 3) return;
  // twice the signed area of the triangle (p0, p1, p_i): the third point's score, and reused by
  // the fourth point's quadrilaterals below
  const double u01 = p.u[i1] - u0, v01 = p.v[i1] - v0;
  double area01[kClipBuffer];
  int i2 = -1;
  best = -1.0;
  for (int i = 0; i < n; ++i) {
    area01[i] = u01 * (p.v[i] - v0) - v01 * (p.u[i] - u0);
    const double a = std::abs(area01[i]);
    if (!keep[i] && a > best) {
      best = a;
      i2 = i;
    }
  }
  if (i2 < 0) return;
  keep[i2] = true;
  if (max_points < 4) return;
  // twice the area of the hull of p0, p1, p2 and candidate p_i (in convex position): the largest
  // of the quadrilaterals p0 p1 p2 p_i, p0 p1 p_i p2 and p0 p2 p1 p_i. With the signed triangle
  // areas A012, A02i and A01i, those are |A012 + A02i|, |A01i - A02i| and |A01i - A012|: swapping
  // two vertices of a triangle negates its area exactly, since each product commutes exactly.
  const double a012 = area01[i2];
  const double u02 = p.u[i2] - u0, v02 = p.v[i2] - v0;
  int i3 = -1;
  best = -1.0;
  for (int i = 0; i < n; ++i) {
    const double a02i = u02 * (p.v[i] - v0) - v02 * (p.u[i] - u0);
    const double a01i = area01[i];
    const double a =
        std::max(std::abs(a012 + a02i), std::max(std::abs(a01i - a02i), std::abs(a01i - a012)));
    if (!keep[i] && a > best) {
      best = a;
      i3 = i;
    }
  }
  if (i3 >= 0) keep[i3] = true;
}

// face contact: reference box R, face k with outward normal sign_m * (axis k of R) pointing at
// the incident box I, whose rotation and position in R's frame are R_RI and p_RI. `n_W` is the
// contact normal to report (from geom 2 to geom 1).
int FaceContact(const GeomPose& ref, const Vec3& ref_half_m, int k, double sign_m, const Mat3& R_RI,
                const Vec3& p_RI, const Vec3& inc_half_m, const Vec3& n_W, ContactPoint* out,
                int max_points) {
  // incident face: the one whose normal is most anti-parallel to the reference normal
  int l = 0;
  for (int j = 1; j < 3; ++j) {
    if (std::abs(R_RI(k, j)) > std::abs(R_RI(k, l))) l = j;
  }
  const double sign_l = -Sign(sign_m * R_RI(k, l));
  const int l1 = kNext1[l], l2 = kNext2[l];
  const int k1 = kNext1[k], k2 = kNext2[k];
  // the incident face's corners centre +- e1 +- e2 (the signs (+, +), (-, +), (-, -), (+, -) in
  // turn) in R's frame, only the three coordinates the clipping needs: u along k1, v along k2,
  // the height along k
  FacePolygon poly[2];
  FacePolygon* cur = &poly[0];
  FacePolygon* next = &poly[1];
  const double centre_scale = sign_l * inc_half_m[l];
  const int axes[3] = {k1, k2, k};
  double corner[3][4];
  for (int c = 0; c < 3; ++c) {
    const int r = axes[c];
    const double centre = p_RI[r] + centre_scale * R_RI(r, l);
    const double e1 = inc_half_m[l1] * R_RI(r, l1);
    const double e2 = inc_half_m[l2] * R_RI(r, l2);
    const double plus = centre + e1, minus = centre - e1;
    corner[c][0] = plus + e2;
    corner[c][1] = minus + e2;
    corner[c][2] = minus - e2;
    corner[c][3] = plus - e2;
  }
  for (int i = 0; i < 4; ++i) {
    cur->u[i] = corner[0][i];
    cur->v[i] = corner[1][i];
    cur->z[i] = sign_m * corner[2][i] - ref_half_m[k];
  }
  cur->n = 4;
  // clip against the reference face's four side planes. On a resting pair every corner usually
  // passes all four tests already, or misses by a sliver (kCornerTolerance), and then no step
  // needs to cut: 16 tests (in ClipPolygon's arithmetic, up to the tolerance) decide that at once
  const double limit1 = ref_half_m[k1], limit2 = ref_half_m[k2];
  const double slack1 = kCornerTolerance * limit1, slack2 = kCornerTolerance * limit2;
  bool inside = true;
  for (int i = 0; i < 4; ++i) {
    const double u = cur->u[i], v = cur->v[i];
    inside = inside & (u - limit1 <= slack1) & (-u - limit1 <= slack1) & (v - limit2 <= slack2) &
             (-v - limit2 <= slack2);
  }
  if (inside) {
    // a corner inside stays where it is; one past a side by at most the slack moves onto it
    for (int i = 0; i < 4; ++i) {
      cur->u[i] = std::clamp(cur->u[i], -limit1, limit1);
      cur->v[i] = std::clamp(cur->v[i], -limit2, limit2);
    }
  } else {
    // a step that keeps every vertex leaves the polygon where it is
    if (ClipPolygon<false, false>(*cur, limit1, *next)) std::swap(cur, next);
    if (ClipPolygon<false, true>(*cur, limit1, *next)) std::swap(cur, next);
    if (ClipPolygon<true, false>(*cur, limit2, *next)) std::swap(cur, next);
    if (ClipPolygon<true, true>(*cur, limit2, *next)) std::swap(cur, next);
  }
  // keep the points below the reference face, in place (a point moves only to a lower index)
  FacePolygon& b = *cur;
  int below = 0;
  for (int i = 0; i < b.n; ++i) {
    b.u[below] = b.u[i];
    b.v[below] = b.v[i];
    b.z[below] = b.z[i];
    below += b.z[i] < 0.0 ? 1 : 0;
  }
  b.n = below;
  bool keep[kClipBuffer];
  const bool reduce = below > max_points;
  if (reduce) ReduceManifold(b, max_points, keep);
  int count = 0;
  for (int i = 0; i < below; ++i) {
    if (reduce && !keep[i]) continue;
    Vec3 x_R;
    x_R[k1] = b.u[i];
    x_R[k2] = b.v[i];
    // midpoint between the incident point (height z) and its projection on the face
    x_R[k] = sign_m * (ref_half_m[k] + 0.5 * b.z[i]);
    out[count++] = {ref.p_W + ref.R_WG * x_R, n_W, -b.z[i]};
  }
  return count;
}

// the 9 edge axes a_i x b_j of a box pair, written in A's frame as e_i x C.col(j), with the
// best one so far. Separates<i, j> takes the indices as template arguments so that every matrix
// entry it reads is at a fixed offset: the 9 tests then need no index arithmetic.
struct EdgeAxes {
  const Mat3& C;     // C(i, j) = a_i . b_j
  const Mat3& absC;  // |C|
  const Vec3& d_A;   // B's centre minus A's, in A's frame
  const Vec3& a_m;   // half-extents
  const Vec3& b_m;
  double sep;  // the separation to beat, then the best edge axis's
  int edge_i = -1, edge_j = -1;

  // true if axis a_i x b_j separates the boxes; otherwise records it if it beats `sep`
  template <int i, int j>
  bool Separates() {
    constexpr int i1 = kNext1[i], i2 = kNext2[i];
    constexpr int j1 = kNext1[j], j2 = kNext2[j];
    const double length2 = C(i1, j) * C(i1, j) + C(i2, j) * C(i2, j);
    if (length2 < kMinEdgeAxisSine * kMinEdgeAxisSine) return false;
    const double centre_m = d_A[i2] * C(i1, j) - d_A[i1] * C(i2, j);
    const double radius_a_m = a_m[i1] * absC(i2, j) + a_m[i2] * absC(i1, j);
    const double radius_b_m = b_m[j1] * absC(i, j2) + b_m[j2] * absC(i, j1);
    // separation times the axis length
    const double s_scaled = std::abs(centre_m) - radius_a_m - radius_b_m;
    if (s_scaled >= 0.0) return true;
    // both negative: s_scaled / length > sep iff s_scaled^2 < sep^2 length^2, so only such
    // candidates need their normalised separation
    if (sep < 0.0 && s_scaled * s_scaled < sep * sep * length2) {
      const double s = s_scaled / std::sqrt(length2);
      if (s > sep) {
        sep = s;
        edge_i = i;
        edge_j = j;
      }
    }
    return false;
  }
};

// box A (geom 1) against box B (geom 2), separating axis test over 15 axes in A's frame
int BoxBox(const GeomPose& box_a, const Vec3& a_m, const GeomPose& box_b, const Vec3& b_m,
           ContactPoint* out, int max_points) {
  // C(i, j) = a_i . b_j and the centre offset in both frames, each a 3-term dot product summed
  // left to right (as Eigen's products do), written out to spare their packing and unpacking
  const Mat3& Ra = box_a.R_WG;
  const Mat3& Rb = box_b.R_WG;
  Mat3 C, absC;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      C(i, j) = Ra(0, i) * Rb(0, j) + Ra(1, i) * Rb(1, j) + Ra(2, i) * Rb(2, j);
      absC(i, j) = std::abs(C(i, j));
    }
  }
  const Vec3 d_W = box_b.p_W - box_a.p_W;
  Vec3 d_A, d_B;
  for (int i = 0; i < 3; ++i) {
    d_A[i] = Ra(0, i) * d_W[0] + Ra(1, i) * d_W[1] + Ra(2, i) * d_W[2];
    d_B[i] = Rb(0, i) * d_W[0] + Rb(1, i) * d_W[1] + Rb(2, i) * d_W[2];
  }
  // separations (negative: penetration) along A's face normals, then B's
  constexpr double kNone = -std::numeric_limits<double>::infinity();
  double sep_a = kNone, sep_b = kNone;
  int face_a = 0, face_b = 0;
  for (int i = 0; i < 3; ++i) {
    const double s = std::abs(d_A[i]) - (a_m[i] + absC.row(i).dot(b_m));
    if (s >= 0.0) return 0;
    if (s > sep_a) {
      sep_a = s;
      face_a = i;
    }
  }
  for (int j = 0; j < 3; ++j) {
    const double s = std::abs(d_B[j]) - (b_m[j] + absC.col(j).dot(a_m));
    if (s >= 0.0) return 0;
    if (s > sep_b) {
      sep_b = s;
      face_b = j;
    }
  }
  // prefer A's faces, then B's, then edges (Box2D's and ODE's bias for stable manifolds)
  const bool use_b = sep_b > kAxisRelativeTolerance * sep_a + kAxisAbsoluteTolerance_m;
  const double sep_face = use_b ? sep_b : sep_a;
  // edge axes a_i x b_j: each is tested for separation; one replaces the face axis only if it
  // separates more than kAxisRelativeTolerance * sep_face + kAxisAbsoluteTolerance_m
  const double to_beat = kAxisRelativeTolerance * sep_face + kAxisAbsoluteTolerance_m;
  EdgeAxes edges{C, absC, d_A, a_m, b_m, to_beat};
  // in the order i = 0..2, j = 0..2 within, which decides ties
  if (edges.Separates<0, 0>() || edges.Separates<0, 1>() || edges.Separates<0, 2>() ||
      edges.Separates<1, 0>() || edges.Separates<1, 1>() || edges.Separates<1, 2>() ||
      edges.Separates<2, 0>() || edges.Separates<2, 1>() || edges.Separates<2, 2>()) {
    return 0;
  }
  const double sep_e = edges.sep;
  const int edge_i = edges.edge_i, edge_j = edges.edge_j;
  if (edge_i >= 0) {
    const Vec3 ua_W = box_a.R_WG.col(edge_i), ub_W = box_b.R_WG.col(edge_j);
    // normal from B to A
    Vec3 n_W = ua_W.cross(ub_W).normalized();
    if (n_W.dot(d_W) > 0.0) n_W = -n_W;
    // the edge of A nearest B (support point of A along -n) and of B nearest A (along +n)
    Vec3 xa_W = box_a.p_W, xb_W = box_b.p_W;
    for (int k = 0; k < 3; ++k) {
      if (k != edge_i) xa_W -= Sign(n_W.dot(box_a.R_WG.col(k))) * a_m[k] * box_a.R_WG.col(k);
      if (k != edge_j) xb_W += Sign(n_W.dot(box_b.R_WG.col(k))) * b_m[k] * box_b.R_WG.col(k);
    }
    // closest points of the two edge lines, clamped to the edges
    const Vec3 w_W = xa_W - xb_W;
    const double c = ua_W.dot(ub_W), da = ua_W.dot(w_W), db = ub_W.dot(w_W);
    const double denom = 1.0 - c * c;  // >= kMinEdgeAxisSine^2: the edges are not parallel
    const double sa = std::clamp((c * db - da) / denom, -a_m[edge_i], a_m[edge_i]);
    const double sb = std::clamp((db - c * da) / denom, -b_m[edge_j], b_m[edge_j]);
    out[0] = {0.5 * ((xa_W + sa * ua_W) + (xb_W + sb * ub_W)), n_W, -sep_e};
    return 1;
  }
  if (use_b) {
    // B's face towards A is the reference; the normal from B to A is its outward normal
    const double sign_m = -Sign(d_B[face_b]);
    const Vec3 n_W = sign_m * box_b.R_WG.col(face_b);
    return FaceContact(box_b, b_m, face_b, sign_m, C.transpose(), -d_B, a_m, n_W, out, max_points);
  }
  const double sign_m = Sign(d_A[face_a]);
  const Vec3 n_W = -sign_m * box_a.R_WG.col(face_a);
  return FaceContact(box_a, a_m, face_a, sign_m, C, d_A, b_m, n_W, out, max_points);
}

// dispatch with geom 1 of a type no later than geom 2's in sphere, box, plane order
int CollideOrdered(GeomType t1, const Vec3& size1, const GeomPose& pose1, GeomType t2,
                   const Vec3& size2, const GeomPose& pose2, ContactPoint* out, int capacity) {
  if (t1 == GeomType::kSphere) {
    switch (t2) {
      case GeomType::kSphere:
        return SphereSphere(pose1.p_W, size1.x(), pose2.p_W, size2.x(), out);
      case GeomType::kBox:
        return SphereBox(pose1.p_W, size1.x(), pose2, size2, out);
      case GeomType::kPlane:
        return SpherePlane(pose1.p_W, size1.x(), pose2, out);
      default:
        return 0;
    }
  }
  if (t1 == GeomType::kBox) {
    const int max_points = capacity < kMaxManifoldPoints ? capacity : kMaxManifoldPoints;
    switch (t2) {
      case GeomType::kBox:
        return BoxBox(pose1, size1, pose2, size2, out, max_points);
      case GeomType::kPlane:
        return BoxPlane(pose1, size1, pose2, out, max_points);
      default:
        return 0;
    }
  }
  return 0;
}

// position of a type in the canonical order of CollideOrdered
int Rank(GeomType t) {
  switch (t) {
    case GeomType::kSphere:
      return 0;
    case GeomType::kBox:
      return 1;
    case GeomType::kPlane:
      return 2;
    default:
      return 3;
  }
}

}  // namespace

bool HasNarrowPhase(GeomType a, GeomType b) {
  const int ra = Rank(a), rb = Rank(b);
  return ra < 3 && rb < 3 && !(ra == 2 && rb == 2);
}

int Collide(GeomType t1, const Vec3& size1, const GeomPose& pose1, GeomType t2, const Vec3& size2,
            const GeomPose& pose2, ContactPoint* out, int capacity) {
  if (out == nullptr || capacity <= 0 || !HasNarrowPhase(t1, t2)) return 0;
  if (!PoseFinite(pose1) || !PoseFinite(pose2)) return 0;
  if (!SizeValid(t1, size1) || !SizeValid(t2, size2)) return 0;
  if (capacity > kMaxPairContacts) capacity = kMaxPairContacts;
  return CollideAccepted(t1, size1, pose1, t2, size2, pose2, out, capacity);
}

int CollideAccepted(GeomType t1, const Vec3& size1, const GeomPose& pose1, GeomType t2,
                    const Vec3& size2, const GeomPose& pose2, ContactPoint* out, int capacity) {
  int n = 0;
  if (Rank(t1) <= Rank(t2)) {
    n = CollideOrdered(t1, size1, pose1, t2, size2, pose2, out, capacity);
  } else {
    // swapped: same points, normal from the other geom
    n = CollideOrdered(t2, size2, pose2, t1, size1, pose1, out, capacity);
    for (int i = 0; i < n; ++i) out[i].n_W = -out[i].n_W;
  }
  // finite input can still overflow (e.g. sizes near the largest double)
  return PointsFinite(out, n) ? n : 0;
}

}  // namespace rigidtouch::geometry
