#include "bench/mujoco_engine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

namespace rigidtouch::bench {
namespace {

const EngineRegistrar kMujocoRegistrar{"mujoco", &MakeMujocoEngine};

bool AllFiniteMjNum(const mjtNum* values, int n) {
  return std::all_of(values, values + n, [](mjtNum v) { return std::isfinite(v); });
}

std::string Scientific(double value) {
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%g", value);
  return text.data();
}

}  // namespace

void ApplyMujocoStackingSettings(mjModel& model, const MujocoStackingSettings& settings) {
  mjOption& opt = model.opt;
  opt.solver = settings.solver;
  opt.iterations = settings.iterations;
  opt.tolerance = settings.tolerance;
  opt.cone = settings.elliptic_cone ? mjCONE_ELLIPTIC : mjCONE_PYRAMIDAL;
  opt.impratio = settings.impratio;
  opt.noslip_iterations = settings.noslip_iterations;
  opt.noslip_tolerance = settings.noslip_tolerance;
  // every geom's contact softness: a contact takes the two geoms' (equal) values
  for (int g = 0; g < model.ngeom; ++g) {
    mjtNum* solref = model.geom_solref + mjNREF * g;
    solref[0] = settings.solref_timeconst_s;
    solref[1] = settings.solref_dampratio;
    mjtNum* solimp = model.geom_solimp + mjNIMP * g;
    solimp[0] = settings.solimp_dmin;
    solimp[1] = settings.solimp_dmax;
    solimp[2] = settings.solimp_width_m;
  }
}

std::unique_ptr<mjModel, void (*)(mjModel*)> LoadMjcf(const std::string& path) {
  std::array<char, 1024> error{};
  mjModel* model = mj_loadXML(path.c_str(), nullptr, error.data(), static_cast<int>(error.size()));
  if (model == nullptr) {
    throw Error("scene " + path + " does not load in MuJoCo: " + std::string(error.data()));
  }
  return {model, &mj_deleteModel};
}

int MjBodyId(const mjModel& model, std::string_view body, const std::string& path) {
  const int id = mj_name2id(&model, mjOBJ_BODY, std::string(body).c_str());
  if (id < 0) throw Error("scene " + path + " has no body named '" + std::string(body) + "'");
  return id;
}

MujocoEngine::MujocoEngine() = default;

MujocoEngine::~MujocoEngine() {
  if (snapshot_ != nullptr) mj_deleteData(snapshot_);
  if (data_ != nullptr) mj_deleteData(data_);
  if (model_ != nullptr) mj_deleteModel(model_);
}

void MujocoEngine::Load(const Scene& scene) {
  auto model = LoadMjcf(scene.mjcf_path);
  tool_id_ = MjBodyId(*model, scene.tool_body, scene.mjcf_path);
  settings_ = scene.peer_settings;
  if (settings_ == PeerSettings::kStacking) {
    ApplyMujocoStackingSettings(*model, MujocoStackingSettings());
  }
  if (snapshot_ != nullptr) mj_deleteData(snapshot_);
  if (data_ != nullptr) mj_deleteData(data_);
  if (model_ != nullptr) mj_deleteModel(model_);
  snapshot_ = nullptr;
  path_ = scene.mjcf_path;
  model_ = model.release();
  data_ = mj_makeData(model_);
  // the keyframe 'initial', as rigidtouch starts from it (a drawer half out, a lever at its stop,
  // the arm's servo targets)
  const int key = mj_name2id(model_, mjOBJ_KEY, "initial");
  if (key >= 0) mj_resetDataKeyframe(model_, data_, key);
  tool_force_N_ = scene.tool_force_N;
  // kinematics and contacts of the initial state, so that queries before the first step answer
  mj_forward(model_, data_);
}

void MujocoEngine::Step() {
  // the user's push, at the tool's centre of mass, world frame
  mjtNum* wrench = data_->xfrc_applied + 6 * tool_id_;
  wrench[0] = tool_force_N_.x();
  wrench[1] = tool_force_N_.y();
  wrench[2] = tool_force_N_.z();
  mj_step(model_, data_);
}

int MujocoEngine::ContactCount() const {
  return data_->ncon;
}

int MujocoEngine::BodyContactCount(std::string_view body) const {
  const int id = BodyId(body);
  int count = 0;
  for (int i = 0; i < data_->ncon; ++i) {
    const mjContact& contact = data_->contact[i];
    if (model_->geom_bodyid[contact.geom1] == id || model_->geom_bodyid[contact.geom2] == id) {
      ++count;
    }
  }
  return count;
}

double MujocoEngine::DeepestPenetration_m() const {
  double deepest_m = 0.0;
  for (int i = 0; i < data_->ncon; ++i) deepest_m = std::max(deepest_m, -data_->contact[i].dist);
  return deepest_m;
}

double MujocoEngine::BodyPenetration_m(std::string_view body) const {
  const int id = BodyId(body);
  double deepest_m = 0.0;
  for (int i = 0; i < data_->ncon; ++i) {
    const mjContact& contact = data_->contact[i];
    if (model_->geom_bodyid[contact.geom1] == id || model_->geom_bodyid[contact.geom2] == id) {
      deepest_m = std::max(deepest_m, -contact.dist);
    }
  }
  return deepest_m;
}

double MujocoEngine::JointPosition(std::string_view joint) const {
  const int id = mj_name2id(model_, mjOBJ_JOINT, std::string(joint).c_str());
  if (id < 0 || (model_->jnt_type[id] != mjJNT_HINGE && model_->jnt_type[id] != mjJNT_SLIDE)) {
    throw Error("scene " + path_ + " has no hinge or slide joint named '" + std::string(joint) +
                "'");
  }
  return data_->qpos[model_->jnt_qposadr[id]];
}

int MujocoEngine::FreeQposAddress(int body_id) const {
  if (model_->body_jntnum[body_id] != 1) return -1;
  const int joint = model_->body_jntadr[body_id];
  if (model_->jnt_type[joint] != mjJNT_FREE) return -1;
  return model_->jnt_qposadr[joint];
}

int MujocoEngine::BodyId(std::string_view body) const {
  return MjBodyId(*model_, body, path_);
}

Vec3 MujocoEngine::BodyPosition(std::string_view body) const {
  const int id = BodyId(body);
  // after mj_step xpos still holds the pose the step started from; a free body's qpos is current
  const int adr = FreeQposAddress(id);
  const mjtNum* p = adr >= 0 ? data_->qpos + adr : data_->xpos + 3 * id;
  return Vec3(p[0], p[1], p[2]);
}

Quat MujocoEngine::BodyOrientation(std::string_view body) const {
  const int id = BodyId(body);
  const int adr = FreeQposAddress(id);
  const mjtNum* q = adr >= 0 ? data_->qpos + adr + 3 : data_->xquat + 4 * id;
  return Quat(q[0], q[1], q[2], q[3]).normalized();
}

void MujocoEngine::SetBodyMotion(std::string_view body, const Vec3& position_m,
                                 const Vec3& velocity_mps) {
  const int id = BodyId(body);
  const int adr = FreeQposAddress(id);
  if (adr < 0) throw Error("body '" + std::string(body) + "' in " + path_ + " is not free");
  const int dof = model_->jnt_dofadr[model_->body_jntadr[id]];
  mjtNum* qpos = data_->qpos + adr;
  mjtNum* qvel = data_->qvel + dof;
  for (int k = 0; k < 3; ++k) {
    qpos[k] = position_m[k];
    qvel[k] = velocity_mps[k];  // free joint: linear velocity in the world frame
    qvel[3 + k] = 0.0;
  }
  qpos[3] = 1.0;
  qpos[4] = qpos[5] = qpos[6] = 0.0;
}

void MujocoEngine::SaveSnapshot() {
  // a full copy: positions, velocities and the solver's warm start come back together
  snapshot_ = mj_copyData(snapshot_, model_, data_);
}

void MujocoEngine::RestoreSnapshot() {
  mj_copyData(data_, model_, snapshot_);
}

bool MujocoEngine::StateIsFinite() const {
  return AllFiniteMjNum(data_->qpos, model_->nq) && AllFiniteMjNum(data_->qvel, model_->nv);
}

long MujocoEngine::WarningCount() const {
  long count = 0;
  for (int i = 0; i < mjNWARNING; ++i) count += data_->warning[i].number;
  return count;
}

std::string MujocoEngine::Configuration() const {
  static constexpr const char* kSolvers[] = {"PGS", "CG", "Newton"};
  static constexpr const char* kCones[] = {"pyramidal", "elliptic"};
  const mjOption& opt = model_->opt;
  std::string line =
      std::string("MuJoCo ") + mj_versionString() + ", settings " + PeerSettingsName(settings_) +
      ": solver " + kSolvers[opt.solver] + ", iterations " + std::to_string(opt.iterations) +
      ", tolerance " + Scientific(opt.tolerance) + ", cone " + kCones[opt.cone] + ", impratio " +
      Scientific(opt.impratio) + ", noslip iterations " + std::to_string(opt.noslip_iterations);
  if (model_->ngeom > 0) {
    // every geom has the same values in the benchmark scenes; the first one's are printed
    const mjtNum* solref = model_->geom_solref;
    const mjtNum* solimp = model_->geom_solimp;
    line += ", geom solref " + Scientific(solref[0]) + " " + Scientific(solref[1]) + ", solimp " +
            Scientific(solimp[0]) + " " + Scientific(solimp[1]) + " " + Scientific(solimp[2]);
  }
  line += std::string(", integrator ") +
          (opt.integrator == mjINT_EULER ? "Euler"
           : opt.integrator == mjINT_RK4 ? "RK4"
                                         : "implicit") +
          ", timestep " + Scientific(opt.timestep) + " s, nconmax " +
          std::to_string(model_->nconmax) + ", njmax " + std::to_string(model_->njmax);
  return line;
}

std::unique_ptr<Engine> MakeMujocoEngine() {
  return std::make_unique<MujocoEngine>();
}

}  // namespace rigidtouch::bench
