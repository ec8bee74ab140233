// rigidtouch in the benchmark suite: the same scenes, the same constant tool force, the default
// renderer (the impulse train at 250 Hz, t_c = 0.1 s), the default scene contact law, and a tool
// contact as stiff as a simulated body's.
#include <algorithm>
#include <cmath>
#include <sstream>

#include "bench/engine.h"
#include "dynamics/tree.h"
#include "engine/workspace.h"
#include "io/config.h"
#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::bench {
namespace {

// the name of the two-thread engine
constexpr std::string_view kTwoThreadsName = "rigidtouch_2threads";

class RigidtouchEngine final : public Engine {
 public:
  // threads 2: the second engine, "rigidtouch_2threads", the same tick with the worker thread
  // (the same results bit for bit; the peers run one thread)
  explicit RigidtouchEngine(int threads) : threads_(threads) {}
  std::string_view Name() const override {
    return threads_ == 1 ? kReferenceEngine : kTwoThreadsName;
  }

  void Load(const Scene& scene) override {
    LoadOptions options;
    options.tool_name = scene.tool_body;
    // the tool is a simulated body here, not a haptic wall: a contact as stiff as the peers'
    // (the haptic default, 2000 N/m, lets the pile's 0.6 m/s tool drop sink 4.3 mm while the
    // train works, and 5e4 N/m makes the tool roll on the stack; 2e4 passes every gate)
    options.contact.stiffness_N_per_m = 2.0e4;
    options.contact.damping_Ns_per_m = 15.0;
    options.threads = threads_;
    model_ = std::make_unique<Model>(LoadModel(scene.mjcf_path, options));
    data_ = std::make_unique<Data>(MakeData(*model_));
    input_.tool_wrench.force_N = scene.tool_force_N;
  }

  void Step() override { Tick(*model_, *data_, input_); }

  int ContactCount() const override { return data_->ncontact; }

  int BodyContactCount(std::string_view body) const override {
    const int b = Index(body);
    int n = 0;
    for (int c = 0; c < data_->ncontact; ++c) {
      n += data_->contacts[c].body_a == b || data_->contacts[c].body_b == b;
    }
    return n;
  }

  double DeepestPenetration_m() const override {
    double d = 0.0;
    for (int c = 0; c < data_->ncontact; ++c) d = std::max(d, data_->contacts[c].depth_m);
    return d;
  }

  double BodyPenetration_m(std::string_view body) const override {
    const int b = Index(body);
    double d = 0.0;
    for (int c = 0; c < data_->ncontact; ++c) {
      const Contact& contact = data_->contacts[c];
      if (contact.body_a == b || contact.body_b == b) d = std::max(d, contact.depth_m);
    }
    return d;
  }

  double JointPosition(std::string_view joint) const override {
    for (std::size_t t = 0; t < model_->trees.size(); ++t) {
      for (const JointModel& j : model_->trees[t].joints) {
        if (j.name == joint && (j.type == JointKind::kHinge || j.type == JointKind::kSlide)) {
          return data_->trees[t]->qpos[j.qpos_adr];
        }
      }
    }
    throw Error("no hinge or slide joint named '" + std::string(joint) + "' in " + model_->source);
  }

  Vec3 BodyPosition(std::string_view body) const override { return data_->bodies[Index(body)].x_W; }

  Quat BodyOrientation(std::string_view body) const override {
    const int b = Index(body);
    return data_->bodies[b].q_WB * model_->bodies[b].iquat_B.conjugate();
  }

  void SetBodyMotion(std::string_view body, const Vec3& position_m,
                     const Vec3& velocity_mps) override {
    BodyState& s = data_->bodies[Index(body)];
    s.x_W = position_m;
    s.v_W = velocity_mps;
    s.w_W.setZero();
  }

  // the state that carries over between ticks: bodies, the last tick's contacts (identity,
  // anchors: they become `previous` at the next tick) and the collision windows
  void SaveSnapshot() override {
    snapshot_.bodies = data_->bodies;
    snapshot_.contacts = data_->contacts;
    snapshot_.ncontact = data_->ncontact;
    snapshot_.window = data_->window;
    snapshot_.step = data_->step;
    snapshot_.next_contact_id = data_->workspace->collision.matching.next_contact_id;
    // the trees' joint state with their kinematics and scratch, limits and windows
    snapshot_.trees.clear();
    for (const auto& tree : data_->trees) snapshot_.trees.push_back(*tree);
    snapshot_.joint_at_limit = data_->joint_at_limit;
    snapshot_.tree_window = data_->tree_window;
    // the link geoms' poses, which the trees stage writes after integrating and collision reads
    // at the next tick
    snapshot_.geom_poses = data_->workspace->collision.poses;
    snapshot_.geom_check = data_->workspace->collision.geom_check;
  }

  void RestoreSnapshot() override {
    std::copy(snapshot_.bodies.begin(), snapshot_.bodies.end(), data_->bodies.begin());
    std::copy(snapshot_.contacts.begin(), snapshot_.contacts.end(), data_->contacts.begin());
    data_->ncontact = snapshot_.ncontact;
    std::copy(snapshot_.window.begin(), snapshot_.window.end(), data_->window.begin());
    data_->step = snapshot_.step;
    data_->time_s = static_cast<double>(snapshot_.step) * model_->timestep_s;
    data_->workspace->collision.matching.next_contact_id = snapshot_.next_contact_id;
    for (std::size_t t = 0; t < data_->trees.size(); ++t) *data_->trees[t] = snapshot_.trees[t];
    data_->joint_at_limit = snapshot_.joint_at_limit;
    std::copy(snapshot_.tree_window.begin(), snapshot_.tree_window.end(),
              data_->tree_window.begin());
    data_->workspace->collision.poses = snapshot_.geom_poses;
    data_->workspace->collision.geom_check = snapshot_.geom_check;
  }

  bool StateIsFinite() const override {
    for (const BodyState& s : data_->bodies) {
      if (!s.x_W.allFinite() || !s.v_W.allFinite() || !s.w_W.allFinite()) return false;
    }
    for (const auto& tree : data_->trees) {
      if (!tree->qpos.allFinite() || !tree->qvel.allFinite()) return false;
    }
    return true;
  }

  long WarningCount() const override {
    long n = 0;
    for (const WarningStat& w : data_->warnings) n += w.count;
    return n;
  }

  std::string Configuration() const override {
    std::ostringstream s;
    const Model& m = *model_;
    s << "rigidtouch: renderer " << text::RendererName(m.render.renderer) << " (f "
      << m.render.frequency_hz << " Hz, t_c " << m.render.t_collision_s << " s), h " << m.timestep_s
      << " s, tool contact k " << m.contact.stiffness_N_per_m << " N/m b "
      << m.contact.damping_Ns_per_m << " N s/m (explicit), scene contact k "
      << m.contact.scene_stiffness_N_per_m << " N/m b " << m.contact.scene_damping_Ns_per_m
      << " N s/m (implicit), own narrow phase for plane/sphere/box, threads " << m.threads;
    return s.str();
  }

 private:
  int Index(std::string_view name) const {
    for (std::size_t i = 0; i < model_->bodies.size(); ++i) {
      if (model_->bodies[i].name == name) return static_cast<int>(i);
    }
    throw Error("no body named '" + std::string(name) + "' in " + model_->source);
  }

  struct Snapshot {
    std::vector<BodyState> bodies;
    std::vector<Contact> contacts;
    int ncontact = 0;
    std::vector<WindowState> window;
    std::int64_t step = 0;
    int next_contact_id = 0;
    std::vector<dynamics::TreeData> trees;
    std::vector<std::vector<unsigned char>> joint_at_limit;
    std::vector<WindowState> tree_window;
    std::vector<geometry::GeomPose> geom_poses;
    std::vector<geometry::GeomCheck> geom_check;
  };

  int threads_ = 1;
  std::unique_ptr<Model> model_;
  std::unique_ptr<Data> data_;
  TickInput input_;
  Snapshot snapshot_;
};

const EngineRegistrar registrar("rigidtouch",
                                [] { return std::unique_ptr<Engine>(new RigidtouchEngine(1)); });
const EngineRegistrar registrar_2threads(std::string(kTwoThreadsName), [] {
  return std::unique_ptr<Engine>(new RigidtouchEngine(2));
});

}  // namespace
}  // namespace rigidtouch::bench
