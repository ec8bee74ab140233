// Scene loading: MJCF compiled by libmujoco, copied into rigidtouch's Model (docs/architecture.md).
// Every number copied is checked against the bounds of docs/decisions.md ("Scene bounds"): MuJoCo
// compiles 1e300 masses and NaN keyframes without complaint, and a tick on them yields NaN.
#include <mujoco/mujoco.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "base/limits.h"
#include "geometry/capacity.h"
#include "io/mjcf_articulation.h"
#include "io/mjcf_checks.h"
#include "io/mjcf_compile.h"
#include "io/mjcf_errors.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch {
namespace {

std::string MjName(const mjModel* m, int type, int id) {
  const char* name = mj_id2name(m, type, id);
  if (name != nullptr && name[0] != '\0') return name;
  std::ostringstream s;
  s << "#" << id;
  return s.str();
}

const char* MjGeomTypeName(int type) {
  switch (type) {
    case mjGEOM_PLANE:
      return "plane";
    case mjGEOM_HFIELD:
      return "hfield";
    case mjGEOM_SPHERE:
      return "sphere";
    case mjGEOM_CAPSULE:
      return "capsule";
    case mjGEOM_ELLIPSOID:
      return "ellipsoid";
    case mjGEOM_CYLINDER:
      return "cylinder";
    case mjGEOM_BOX:
      return "box";
    case mjGEOM_MESH:
      return "mesh";
    default:
      return "unknown";
  }
}

// rigidtouch's geom type for a MuJoCo one, or false for a height field (no pair function of
// MuJoCo's collides it with a geom outside the compiled model's own collision pipeline).
// Cylinders and ellipsoids take MuJoCo's pair functions as meshes do (GeomType::kMesh, with
// GeomModel::mj_type telling them apart): a cylinder on a plane gets up to four points, against
// anything else one MPR point per tick.
bool ToGeomType(int mj_type, GeomType* out) {
  switch (mj_type) {
    case mjGEOM_PLANE:
      *out = GeomType::kPlane;
      return true;
    case mjGEOM_SPHERE:
      *out = GeomType::kSphere;
      return true;
    case mjGEOM_CAPSULE:
      *out = GeomType::kCapsule;
      return true;
    case mjGEOM_BOX:
      *out = GeomType::kBox;
      return true;
    case mjGEOM_MESH:
      *out = GeomType::kMesh;
      return true;
    case mjGEOM_CYLINDER:  // convex shapes that only MuJoCo's pair functions collide, like meshes
    case mjGEOM_ELLIPSOID:
      *out = GeomType::kMesh;
      return true;
    default:
      return false;
  }
}

// scene bounds (docs/decisions.md, "Scene bounds"): wide enough for any haptic scene, narrow
// enough that products of them (m v^2, k x, m g) stay far from overflow
constexpr double kMinMass = 1e-9, kMaxMass = 1e9;  // kg
constexpr double kMaxInertia = 1e9;                // kg m^2 (and > 0)
constexpr double kMinSize = 1e-9, kMaxSize = 1e9;  // m, geom sizes
constexpr double kMaxPosition = 1e4;               // m, |coordinate| of poses and keys
constexpr double kMaxSpeed = 1e3;                  // m/s, keyframe linear velocity
constexpr double kMaxAngularSpeed = 1e4;           // rad/s, keyframe angular velocity
constexpr double kMaxGravity = 1e3;                // m/s^2, |gravity|
constexpr double kMaxFriction = 1e2;               // friction coefficient

std::string SceneNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// throws unless v is finite and lo <= v <= hi
void CheckSceneRange(const std::string& path, const std::string& what, double v, double lo,
                     double hi, const char* unit) {
  if (std::isfinite(v) && v >= lo && v <= hi) return;
  throw Error("scene file '" + path + "': " + what + " is " + SceneNumber(v) +
              (unit[0] ? " " : "") + unit + ", outside the valid range [" + SceneNumber(lo) + ", " +
              SceneNumber(hi) + "]" + (unit[0] ? " " : "") + unit);
}

void CheckVec(const std::string& path, const std::string& what, const mjtNum* v, int n,
              double bound, const char* unit) {
  for (int i = 0; i < n; ++i) {
    CheckSceneRange(path, what + "[" + std::to_string(i) + "]", v[i], -bound, bound, unit);
  }
}

Quat MjQuat(const mjtNum* q) {
  return Quat(q[0], q[1], q[2], q[3]);
}

// body state at the centre of mass from a freejoint's qpos (origin, quat) and qvel (world linear
// velocity of the origin, body-frame angular velocity: MuJoCo's convention for free joints)
BodyState StateFromFreejoint(const BodyModel& b, const mjtNum* qpos, const mjtNum* qvel) {
  BodyState s;
  const Vec3 origin_W(qpos[0], qpos[1], qpos[2]);
  const Quat q_W_body = MjQuat(qpos + 3).normalized();
  s.q_WB = (q_W_body * b.iquat_B).normalized();
  const Vec3 com_offset_W = q_W_body * b.ipos_B;
  s.x_W = origin_W + com_offset_W;
  s.w_W = q_W_body * Vec3(qvel[3], qvel[4], qvel[5]);
  s.v_W = Vec3(qvel[0], qvel[1], qvel[2]) + s.w_W.cross(com_offset_W);
  return s;
}

// (pos, quat) given in body b's frame, expressed in the frame of b's ancestor `root` (0: the
// world), by composing MuJoCo's body_pos and body_quat (each relative to the parent) up the chain
void ToAncestor(const mjModel* m, int b, int root, Vec3* pos, Quat* quat) {
  for (; b != root && b != 0; b = m->body_parentid[b]) {
    const Vec3 bp(m->body_pos[3 * b], m->body_pos[3 * b + 1], m->body_pos[3 * b + 2]);
    const Quat bq = MjQuat(m->body_quat + 4 * b).normalized();
    *pos = bp + bq * *pos;
    *quat = bq * *quat;
  }
}

// the mass, centre of mass and principal inertia of free body `root` merged with its welded
// descendants (bodies without joints nested in it: MuJoCo's bodies of body_weldid root), in
// root's frame. MuJoCo keeps welded bodies apart in mjModel; one rigid body is their composite:
// masses add, the centre of mass is the mass-weighted mean, and each part's inertia is rotated
// into root's frame (R diag(I) R^T, R the part's principal frame) and shifted to the common centre
// (parallel-axis theorem: + m (|d|^2 E - d d^T), d the part's centre from the common one). The
// principal axes of the sum are its eigenvectors. Returns the number of bodies merged.
int CompositeInertia(const mjModel* m, int root, BodyModel& body) {
  struct Part {
    double mass;
    Vec3 com;      // in root's frame
    Mat3 inertia;  // about the part's own centre, root's axes
  };
  std::vector<Part> parts;
  for (int c = root; c < m->nbody; ++c) {
    if (c != root && m->body_weldid[c] != root) continue;
    Vec3 com(m->body_ipos[3 * c], m->body_ipos[3 * c + 1], m->body_ipos[3 * c + 2]);
    Quat axes = MjQuat(m->body_iquat + 4 * c).normalized();
    ToAncestor(m, c, root, &com, &axes);
    const Vec3 principal(m->body_inertia[3 * c], m->body_inertia[3 * c + 1],
                         m->body_inertia[3 * c + 2]);
    const Mat3 R = axes.toRotationMatrix();
    parts.push_back(Part{m->body_mass[c], com, R * principal.asDiagonal() * R.transpose()});
  }
  if (parts.size() == 1) {  // nothing welded: MuJoCo's numbers as they are
    body.mass_kg = m->body_mass[root];
    body.inertia_kgm2 = Vec3(m->body_inertia[3 * root], m->body_inertia[3 * root + 1],
                             m->body_inertia[3 * root + 2]);
    body.ipos_B =
        Vec3(m->body_ipos[3 * root], m->body_ipos[3 * root + 1], m->body_ipos[3 * root + 2]);
    body.iquat_B = MjQuat(m->body_iquat + 4 * root).normalized();
    return 1;
  }
  double mass = 0.0;
  Vec3 moment = Vec3::Zero();
  for (const Part& p : parts) {
    mass += p.mass;
    moment += p.mass * p.com;
  }
  body.mass_kg = mass;
  if (!(mass > 0.0)) return static_cast<int>(parts.size());  // refused by the caller
  const Vec3 com = moment / mass;
  Mat3 inertia = Mat3::Zero();
  for (const Part& p : parts) {
    const Vec3 d = p.com - com;
    inertia += p.inertia + p.mass * (d.squaredNorm() * Mat3::Identity() - d * d.transpose());
  }
  inertia = 0.5 * (inertia + inertia.transpose());
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(inertia);
  Mat3 axes = eig.eigenvectors();
  if (axes.determinant() < 0.0) axes.col(2) = -axes.col(2);  // a rotation, not a reflection
  body.inertia_kgm2 = eig.eigenvalues();
  body.ipos_B = com;
  body.iquat_B = Quat(axes).normalized();
  return static_cast<int>(parts.size());
}

// the free bodies: freejoint children of the world without jointed bodies below them are dynamic,
// with the bodies welded into them (no joint of their own) merged in; other joint-less bodies are
// static, or welded into a link of an articulated tree (io::CopyTrees).
// Returns the index in model.bodies of every MuJoCo body (-1: static).
std::vector<int> CopyBodies(const mjModel* m, const std::string& path, Model& model) {
  std::vector<int> body_index(m->nbody, -1);
  for (int b = 1; b < m->nbody; ++b) {
    const std::string name = MjName(m, mjOBJ_BODY, b);
    if (m->body_jntnum[b] == 0) {
      if (m->body_weldid[b] != 0) body_index[b] = body_index[m->body_weldid[b]];
      if (m->body_mocapid[b] >= 0) {
        model.load_warnings.push_back(
            "scene file '" + path + "': body '" + name +
            "' is a mocap body (<body mocap=\"true\">); rigidtouch holds it static at its pose in "
            "the file");
      }
      continue;  // welded into a free body (merged below), or static, welded to the world
    }
    const int jnt = m->body_jntadr[b];
    if (!io::IsLoneFreeBody(m, b)) continue;  // a link of an articulated tree (io::CopyTrees)
    BodyModel body;
    body.name = name;
    const int merged = CompositeInertia(m, b, body);
    body.mj_body = b;
    body.mj_qpos_adr = m->jnt_qposadr[jnt];
    body.mj_qvel_adr = m->jnt_dofadr[jnt];
    if (!(body.mass_kg > 0.0) || !(body.inertia_kgm2.minCoeff() > 0.0)) {
      throw Error("scene file '" + path + "': free body '" + name + "'" +
                  (merged > 1 ? " (with the bodies welded into it)" : "") +
                  " has no positive mass and inertia (give its geoms a mass or density)");
    }
    CheckSceneRange(path, "the mass of body '" + name + "'", body.mass_kg, kMinMass, kMaxMass,
                    "kg");
    for (int i = 0; i < 3; ++i) {
      CheckSceneRange(path, "inertia[" + std::to_string(i) + "] of body '" + name + "'",
                      body.inertia_kgm2[i], 0.0, kMaxInertia, "kg m^2");
    }
    CheckVec(path, "the centre of mass of body '" + name + "'", body.ipos_B.data(), 3, kMaxPosition,
             "m");
    body_index[b] = static_cast<int>(model.bodies.size());
    model.bodies.push_back(body);
  }
  return body_index;
}

// geom g's pose relative to its owner: the body's principal frame, or the world for static geoms.
// A geom of a welded child body is first carried into the free body's frame.
void GeomPose(const mjModel* m, const Model& model, int g, GeomModel& geom) {
  Vec3 pos(m->geom_pos[3 * g], m->geom_pos[3 * g + 1], m->geom_pos[3 * g + 2]);
  Quat quat = MjQuat(m->geom_quat + 4 * g).normalized();
  if (geom.body >= 0) {
    const BodyModel& owner = model.bodies[geom.body];
    ToAncestor(m, m->geom_bodyid[g], owner.mj_body, &pos, &quat);
    geom.pos_B = owner.iquat_B.conjugate() * (pos - owner.ipos_B);
    geom.quat_B = (owner.iquat_B.conjugate() * quat).normalized();
    return;
  }
  // static: compose the chain of static bodies up to the world
  ToAncestor(m, m->geom_bodyid[g], 0, &pos, &quat);
  geom.pos_B = pos;
  geom.quat_B = quat.normalized();
}

// the sizes a geom type uses (a plane's may be 0: infinite), its pose, friction and bound
void CheckGeomNumbers(const mjModel* m, const std::string& path, int g, const GeomModel& geom) {
  const std::string who = "geom '" + geom.name + "'";
  const int mj = m->geom_type[g];
  const int used = mj == mjGEOM_SPHERE                             ? 1
                   : mj == mjGEOM_CAPSULE || mj == mjGEOM_CYLINDER ? 2
                   : mj == mjGEOM_BOX || mj == mjGEOM_ELLIPSOID    ? 3
                                                                   : 0;
  for (int i = 0; i < 3; ++i) {
    const double lo = i < used ? kMinSize : 0.0;
    CheckSceneRange(path, "size[" + std::to_string(i) + "] of " + who, m->geom_size[3 * g + i], lo,
                    kMaxSize, "m");
  }
  if (geom.type != GeomType::kPlane) {
    CheckSceneRange(path, "the bounding radius of " + who, m->geom_rbound[g], 0.0, kMaxSize, "m");
  }
  CheckVec(path, "the position of " + who, m->geom_pos + 3 * g, 3, kMaxPosition, "m");
  CheckSceneRange(path, "the friction of " + who, m->geom_friction[3 * g], 0.0, kMaxFriction, "");
}

void CopyGeoms(const mjModel* m, const std::string& path, const std::vector<int>& body_index,
               const std::vector<io::LinkOf>& link_of, Model& model) {
  for (int g = 0; g < m->ngeom; ++g) {
    GeomModel geom;
    geom.name = MjName(m, mjOBJ_GEOM, g);
    if (!ToGeomType(m->geom_type[g], &geom.type)) {
      throw Error("scene file '" + path + "': geom '" + geom.name + "' has type " +
                  MjGeomTypeName(m->geom_type[g]) +
                  ", which rigidtouch cannot collide; supported types: plane, sphere, capsule, "
                  "box, cylinder, ellipsoid, mesh (convex)");
    }
    geom.body = body_index[m->body_weldid[m->geom_bodyid[g]]];
    const io::LinkOf link = link_of[m->geom_bodyid[g]];
    if (geom.type == GeomType::kPlane && (geom.body >= 0 || link.tree >= 0)) {
      throw Error("scene file '" + path + "': geom '" + geom.name +
                  "' is a plane on a moving body; planes must be static (in the worldbody)");
    }
    CheckGeomNumbers(m, path, g, geom);
    geom.mj_type = m->geom_type[g];
    geom.mjcf_friction = m->geom_friction[3 * g];
    geom.condim = m->geom_condim[g];
    geom.friction = geom.condim == 1 ? 0.0 : geom.mjcf_friction;
    geom.size = Vec3(m->geom_size[3 * g], m->geom_size[3 * g + 1], m->geom_size[3 * g + 2]);
    geom.rbound_m = m->geom_rbound[g];
    geom.contype = m->geom_contype[g];
    geom.conaffinity = m->geom_conaffinity[g];
    GeomPose(m, model, g, geom);
    if (link.tree >= 0) {  // its pose on the link; the world pose at the start is set later
      geom.tree = link.tree;
      geom.link = link.link;
      const int owner = model.trees[link.tree].link_mj_body[link.link];
      geom.pos_L = Vec3(m->geom_pos[3 * g], m->geom_pos[3 * g + 1], m->geom_pos[3 * g + 2]);
      geom.quat_L = MjQuat(m->geom_quat + 4 * g).normalized();
      ToAncestor(m, m->geom_bodyid[g], owner, &geom.pos_L, &geom.quat_L);
    }
    // the pose composed over its bodies: each body's offset may be in range and the sum not (a
    // static body 1e300 m out, a welded chain reaching 1e7 m)
    CheckVec(path,
             "the position of geom '" + geom.name +
                 (geom.body < 0 ? "' in the world" : "' relative to its free body"),
             geom.pos_B.data(), 3, kMaxPosition, "m");
    geom.mj_geom = g;
    model.geoms.push_back(geom);
  }
  // <contact><exclude body1 body2>: MuJoCo's signature is (body1 + 1) << 16 | (body2 + 1), by
  // MJCF body, so it becomes every pair of the two bodies' geoms
  auto& excluded = model.excluded_geom_pairs;
  const int ngeom = static_cast<int>(model.geoms.size());
  for (int e = 0; e < m->nexclude; ++e) {
    const int sig = m->exclude_signature[e];
    const int b1 = (sig >> 16) - 1, b2 = (sig & 0xFFFF) - 1;
    if (b1 < 0 || b2 < 0 || b1 >= m->nbody || b2 >= m->nbody || b1 == b2) continue;
    for (int ga = 0; ga < ngeom; ++ga) {
      if (m->geom_bodyid[model.geoms[ga].mj_geom] != b1) continue;
      for (int gb = 0; gb < ngeom; ++gb) {
        if (m->geom_bodyid[model.geoms[gb].mj_geom] != b2) continue;
        excluded.emplace_back(std::min(ga, gb), std::max(ga, gb));
      }
    }
  }
  std::sort(excluded.begin(), excluded.end());
  excluded.erase(std::unique(excluded.begin(), excluded.end()), excluded.end());
}

int FindTool(Model& model, const std::string& path, const std::string& tool_name) {
  if (tool_name == "none") {  // a placeholder the trees stage holds still (Model::has_tool)
    BodyModel placeholder;
    placeholder.name = "(no tool)";
    placeholder.mass_kg = 1.0;
    placeholder.inertia_kgm2 = Vec3::Constant(1e-3);
    model.has_tool = false;
    model.bodies.push_back(placeholder);
    return static_cast<int>(model.bodies.size()) - 1;
  }
  for (const ArticulatedTree& tree : model.trees) {
    for (const std::string& link : tree.link_names) {
      if (link != tool_name) continue;
      throw Error("scene file '" + path + "': body '" + tool_name +
                  "' is a link of the articulated body '" + tree.name +
                  "'; the tool must be a free body (one <freejoint/> at the top level, no joint "
                  "below it), or pass --tool none for a scene without a tool");
    }
  }
  if (model.bodies.empty()) {
    throw Error("scene file '" + path + "': no free bodies (<freejoint/>) to use as the tool '" +
                tool_name + "'; pass --tool none for a scene without a tool");
  }
  const auto tool = std::find_if(model.bodies.begin(), model.bodies.end(),
                                 [&](const BodyModel& b) { return b.name == tool_name; });
  if (tool == model.bodies.end()) {
    std::string names;
    for (const auto& b : model.bodies) names += (names.empty() ? "" : ", ") + b.name;
    throw Error("scene file '" + path + "': no free body named '" + tool_name +
                "' to use as the tool (free bodies: " + names + "); pass --tool NAME");
  }
  return static_cast<int>(tool - model.bodies.begin());
}

// keyframe "initial" when present, else the model defaults (qpos0, zero qvel)
void InitialState(const mjModel* m, const std::string& path, Model& model) {
  std::vector<mjtNum> qpos(m->qpos0, m->qpos0 + m->nq);
  std::vector<mjtNum> qvel(m->nv, 0.0);
  const int key = mj_name2id(m, mjOBJ_KEY, "initial");
  if (key >= 0) {
    std::copy(m->key_qpos + key * m->nq, m->key_qpos + (key + 1) * m->nq, qpos.begin());
    std::copy(m->key_qvel + key * m->nv, m->key_qvel + (key + 1) * m->nv, qvel.begin());
    if (m->key_time[key] != 0.0) {
      model.load_warnings.push_back("scene file '" + path + "': keyframe 'initial' has time=\"" +
                                    SceneNumber(m->key_time[key]) +
                                    "\"; rigidtouch starts every run at t = 0 and ignores it");
    }
  }
  // only the keyframe named 'initial' is a start: say so of the others rather than drop them
  for (int k = 0; k < m->nkey; ++k) {
    if (k == key) continue;
    const std::string name = MjName(m, mjOBJ_KEY, k);
    model.load_warnings.push_back(
        "scene file '" + path + "': keyframe '" + name +
        "' is not used: rigidtouch starts from the keyframe named 'initial' (name it so to start "
        "from it)");
  }
  const std::string from = key >= 0 ? "keyframe 'initial'" : "the default pose";
  for (const auto& b : model.bodies) {
    if (b.mj_body < 0) continue;  // the placeholder tool: at rest at the origin
    const std::string who = " of body '" + b.name + "' in " + from;
    const mjtNum* q = qpos.data() + b.mj_qpos_adr;
    const mjtNum* v = qvel.data() + b.mj_qvel_adr;
    CheckVec(path, "the position" + who, q, 3, kMaxPosition, "m");
    CheckVec(path, "the quaternion" + who, q + 3, 4, 1e9, "");
    const double norm = std::sqrt(q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]);
    if (!(norm > 1e-9)) throw Error("scene file '" + path + "': the quaternion" + who + " is zero");
    CheckVec(path, "the velocity" + who, v, 3, kMaxSpeed, "m/s");
    CheckVec(path, "the angular velocity" + who, v + 3, 3, kMaxAngularSpeed, "rad/s");
  }
  for (const auto& b : model.bodies) {
    model.initial.push_back(b.mj_body < 0 ? BodyState{}
                                          : StateFromFreejoint(b, qpos.data() + b.mj_qpos_adr,
                                                               qvel.data() + b.mj_qvel_adr));
  }
}

// MuJoCo's warnings while it compiles a scene (a NaN in the XML, ...), kept by the thread that
// compiles so that they become load warnings naming the file, instead of an unprefixed line on
// stdout and a MUJOCO_LOG.TXT in the working directory. MuJoCo's hook is one pointer for the
// process: it is set once (a compilation on each thread keeps its own warnings through the
// thread-local list) and never written again, so concurrent loads do not race on it.
thread_local std::vector<std::string>* t_compile_warnings = nullptr;
void (*g_previous_warning)(const char*) = nullptr;

void KeepCompileWarning(const char* message) {
  if (t_compile_warnings != nullptr) {
    t_compile_warnings->push_back(message);
  } else if (g_previous_warning != nullptr) {
    g_previous_warning(message);  // a hook the host program set before rigidtouch's
  } else {
    std::cerr << "rigidtouch: warning: MuJoCo: " << message << "\n";
  }
}

// this thread's MuJoCo warnings go to `into` while it lives
class CompileWarnings {
 public:
  explicit CompileWarnings(std::vector<std::string>* into) {
    static std::once_flag hooked;
    std::call_once(hooked, [] {
      g_previous_warning = mju_user_warning;
      mju_user_warning = &KeepCompileWarning;
    });
    t_compile_warnings = into;
  }
  ~CompileWarnings() { t_compile_warnings = nullptr; }
  CompileWarnings(const CompileWarnings&) = delete;
  CompileWarnings& operator=(const CompileWarnings&) = delete;
};

// refuses a number that is not finite in the scene file or the files it includes (MuJoCo 2.2.2
// resolves an include relative to the scene file's folder; nesting is bounded, as MuJoCo's own)
void RefuseNonFiniteValues(const std::string& file, const std::filesystem::path& folder,
                           int depth = 0) {
  std::ifstream in(file, std::ios::binary);
  if (!in || depth > 16) return;  // a file that cannot be read is MuJoCo's to report
  const std::string xml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const io::NonFiniteValue bad = io::FindNonFiniteValue(xml);
  if (!bad.element.empty()) {
    throw Error("scene file '" + file + "' line " + std::to_string(bad.line) + ": <" + bad.element +
                "> attribute " + bad.attribute + "=\"" + bad.value +
                "\" is not a finite number (MuJoCo would replace it with its default or keep the "
                "infinity); give a finite value");
  }
  for (const std::string& included : io::IncludedFiles(xml)) {
    RefuseNonFiniteValues((folder / included).string(), folder, depth + 1);
  }
}

}  // namespace

Model LoadModel(const std::string& path, const LoadOptions& options) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw Error("scene file '" + path + "' does not exist or is not a regular file");
  }
  RefuseNonFiniteValues(path, std::filesystem::path(path).parent_path());
  char error[1024] = "";
  std::vector<std::string> mujoco_warnings;
  mjModel* raw = nullptr;
  std::string qhull_report;
  {
    const CompileWarnings kept(&mujoco_warnings);
    // without MuJoCo's solver sizes (rigidtouch sizes its own); Qhull's stderr report kept
    qhull_report = io::WithStderrCaptured(
        [&] { raw = io::CompileWithoutSolverSizes(path, error, sizeof(error)); });
  }
  if (raw == nullptr) {
    throw Error("scene file '" + path + "': " + io::TranslateCompileError(error, qhull_report));
  }
  Model model;
  for (const std::string& w : mujoco_warnings) {
    model.load_warnings.push_back("scene file '" + path + "': MuJoCo: " + w);
  }
  model.collision = std::shared_ptr<mjModel>(raw, [](mjModel* m) { mj_deleteModel(m); });
  const mjModel* m = raw;
  model.source = path;
  model.timestep_s = options.timestep_s.value_or(m->opt.timestep);
  // the scene's own step, named where it was written (Configure's message would name only the
  // parameter); a step given by the caller is checked, and named, there
  const double h = m->opt.timestep;
  if (!options.timestep_s && !(h >= limits::kMinTimestep_s && h <= limits::kMaxTimestep_s)) {
    throw Error("scene file '" + path + "': <option timestep=\"" + SceneNumber(h) +
                "\"> is out of range: valid " + SceneNumber(limits::kMinTimestep_s) + " to " +
                SceneNumber(limits::kMaxTimestep_s) +
                " s (or give the time step in the config or a flag)");
  }
  model.gravity_W = Vec3(m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2]);
  if (!model.gravity_W.allFinite() || model.gravity_W.norm() > kMaxGravity) {
    throw Error("scene file '" + path + "': option gravity (" + SceneNumber(model.gravity_W.x()) +
                " " + SceneNumber(model.gravity_W.y()) + " " + SceneNumber(model.gravity_W.z()) +
                ") m/s^2 is not finite or longer than " + SceneNumber(kMaxGravity) + " m/s^2");
  }

  if (m->opt.disableflags & mjDSBL_GRAVITY) model.gravity_W.setZero();  // <flag gravity="disable"/>
  HonourDisabledConstraints(raw, path, options.tool_name, model.load_warnings);
  model.filter_parent = (m->opt.disableflags & mjDSBL_FILTERPARENT) == 0;
  // bodies and joints first: an actuator or element is then refused naming what it acts on
  const std::vector<int> body_index = CopyBodies(m, path, model);
  const std::vector<io::LinkOf> link_of = io::CopyTrees(m, path, model);
  if (model.bodies.empty() && model.trees.empty()) {
    throw Error("scene file '" + path +
                "': no free bodies (<freejoint/>) and no joints; nothing "
                "to simulate");
  }
  CheckElements(m, path, model.load_warnings);
  CopyGeoms(m, path, body_index, link_of, model);
  io::PlaceLinkGeomsAtStart(model);
  CheckPairs(m, path, model.load_warnings);
  model.tool = FindTool(model, path, options.tool_name);
  InitialState(m, path, model);
  model.contact = options.contact;
  model.render = SceneRender(options.render, model.timestep_s, path, model.load_warnings);
  model.device = options.device;
  model.max_contacts = geometry::MaxContactsFor(model, options.max_contacts);
  model.max_group_bodies = options.max_group_bodies > 0
                               ? std::min<int>(options.max_group_bodies, model.bodies.size())
                               : static_cast<int>(model.bodies.size());
  if (options.threads != 1 && options.threads != 2) {
    throw Error("threads is " + std::to_string(options.threads) + ": valid 1 or 2");
  }
  model.threads = options.threads;
  Configure(model);
  CheckInitialOverlap(model, path);
  return model;
}

}  // namespace rigidtouch
