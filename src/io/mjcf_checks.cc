#include "io/mjcf_checks.h"

#include <cmath>
#include <sstream>

#include "dynamics/kinematics.h"
#include "geometry/collision.h"
#include "io/mjcf_articulation.h"
#include "rigidtouch/types.h"

namespace rigidtouch {
namespace {

std::string Name(const mjModel* m, int type, int id) {
  const char* name = mj_id2name(m, type, id);
  std::string quoted = "'";
  if (name != nullptr && name[0] != '\0') {
    quoted += name;
  } else {
    quoted += '#';
    quoted += std::to_string(id);
  }
  quoted += "'";
  return quoted;
}

std::string Nums(const mjtNum* v, int n) {
  std::ostringstream s;
  for (int i = 0; i < n; ++i) s << (i ? " " : "") << v[i];
  return s.str();
}

bool Differs(const mjtNum* a, const mjtNum* b, int n) {
  for (int i = 0; i < n; ++i) {
    if (a[i] != b[i]) return true;
  }
  return false;
}

const char* EqualityName(int type) {
  switch (type) {
    case mjEQ_CONNECT:
      return "connect";
    case mjEQ_WELD:
      return "weld";
    case mjEQ_JOINT:
      return "joint";
    case mjEQ_TENDON:
      return "tendon";
    default:
      return "distance";
  }
}

// MuJoCo 2.2.2's filter of geoms g1 and g2 (mj_contactFilter), which rigidtouch's broad phase
// applies too: the contype/conaffinity bits, different bodies after welding, and not a body and
// its parent when both move, unless the scene disables filterparent
bool FilterPasses(const mjModel* m, int g1, int g2) {
  if ((m->geom_contype[g1] & m->geom_conaffinity[g2]) == 0 &&
      (m->geom_contype[g2] & m->geom_conaffinity[g1]) == 0) {
    return false;
  }
  const int w1 = m->body_weldid[m->geom_bodyid[g1]], w2 = m->body_weldid[m->geom_bodyid[g2]];
  if (w1 == w2) return false;
  const int p1 = m->body_weldid[m->body_parentid[w1]], p2 = m->body_weldid[m->body_parentid[w2]];
  const bool parent = (m->opt.disableflags & mjDSBL_FILTERPARENT) == 0 && w1 != 0 && w2 != 0;
  return !(parent && (w1 == p2 || w2 == p1));
}

// whether some geom pair of the scene passes the filter (FilterPasses)
bool AnyPairCollides(const mjModel* m) {
  for (int g1 = 0; g1 < m->ngeom; ++g1) {
    for (int g2 = g1 + 1; g2 < m->ngeom; ++g2) {
      if (FilterPasses(m, g1, g2)) return true;
    }
  }
  return false;
}

// a geom's MJCF name in quotes, or its index ('#3')
std::string GeomName(const mjModel* m, const GeomModel& g) {
  return Name(m, mjOBJ_GEOM, g.mj_geom);
}

std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

struct Reporter {
  const std::string& path;
  std::vector<std::string>& warnings;

  [[noreturn]] void Refuse(const std::string& what) const {
    throw Error("scene file '" + path + "': " + what);
  }
  void Warn(const std::string& what) const {
    warnings.push_back("scene file '" + path + "': " + what);
  }
};

// <option> attributes and <flag>s
void CheckOptions(const mjModel* m, const Reporter& r) {
  const mjOption& o = m->opt;
  mjOption def;
  mj_defaultOption(&def);
  if (o.density != 0.0 || o.viscosity != 0.0) {
    r.Refuse("<option density=\"" + Nums(&o.density, 1) + "\" viscosity=\"" +
             Nums(&o.viscosity, 1) +
             "\"> asks for fluid forces (drag, lift, viscosity), which rigidtouch does not "
             "compute; remove them or set them to 0");
  }
  if (o.wind[0] != 0.0 || o.wind[1] != 0.0 || o.wind[2] != 0.0) {
    r.Refuse("<option wind=\"" + Nums(o.wind, 3) +
             "\"> asks for fluid forces, which rigidtouch does not compute; remove it");
  }
  // rigidtouch always computes contacts, limits and dry friction; the flags only change nothing
  // when the scene has none of them: no free body and no geom pair that may collide (links
  // collide with static geometry, free bodies and other links), and for `constraint` no limited
  // joint and no frictionloss either
  bool touching = false, limited = false, friction = false;
  if (o.disableflags & (mjDSBL_CONTACT | mjDSBL_CONSTRAINT)) {
    for (int b = 1; b < m->nbody; ++b) touching = touching || io::IsLoneFreeBody(m, b);
    touching = touching || AnyPairCollides(m);
  }
  for (int j = 0; j < m->njnt; ++j) limited = limited || m->jnt_limited[j] != 0;
  for (int d = 0; d < m->nv; ++d) friction = friction || m->dof_frictionloss[d] != 0.0;
  if ((o.disableflags & mjDSBL_CONTACT) && touching) {
    r.Refuse(
        "<flag contact=\"disable\"/>: rigidtouch always computes contacts (it is a contact "
        "renderer) and this scene has free bodies or geoms that may collide; remove the flag");
  }
  if ((o.disableflags & mjDSBL_CONSTRAINT) && (touching || limited || friction)) {
    r.Refuse(
        "<flag constraint=\"disable\"/> turns contacts, joint limits and frictionloss off, "
        "which rigidtouch always computes (this scene has free bodies, geoms that may collide, "
        "limited joints or frictionloss); remove the flag");
  }
  const std::string unchanged =
      "changes nothing here: the scene has no free body and no geoms that may collide";
  if (o.disableflags & mjDSBL_CONTACT) r.Warn("<flag contact=\"disable\"/> " + unchanged);
  if (o.disableflags & mjDSBL_CONSTRAINT) {
    r.Warn("<flag constraint=\"disable\"/> " + unchanged +
           ", no limited joint and no frictionloss");
  }
  if (o.collision == mjCOL_PAIR) {
    r.Refuse(
        "<option collision=\"predefined\"> collides only <contact><pair> geoms; rigidtouch "
        "collides every pair the contype/conaffinity bits allow");
  }
  if (o.collision == mjCOL_DYNAMIC && m->npair > 0) {
    r.Refuse(
        "<option collision=\"dynamic\"> ignores the <contact><pair> elements; rigidtouch cannot "
        "tell which pairs that leaves out: remove the option or the pairs");
  }
  // flags that tune MuJoCo's solver or features rigidtouch has not got: nothing moves otherwise
  struct Flag {
    int bit;
    const char* name;
  };
  const Flag disable[] = {
      {mjDSBL_EQUALITY, "equality"},   {mjDSBL_FRICTIONLOSS, "frictionloss"},
      {mjDSBL_LIMIT, "limit"},         {mjDSBL_PASSIVE, "passive"},
      {mjDSBL_CLAMPCTRL, "clampctrl"}, {mjDSBL_WARMSTART, "warmstart"},
      {mjDSBL_ACTUATION, "actuation"}, {mjDSBL_REFSAFE, "refsafe"},
      {mjDSBL_SENSOR, "sensor"},
  };
  for (const Flag& f : disable) {
    if (o.disableflags & f.bit) {
      r.Warn(std::string("<flag ") + f.name +
             "=\"disable\"/> is ignored: it tunes a part of MuJoCo that rigidtouch replaces or "
             "does not have");
    }
  }
  const Flag enable[] = {{mjENBL_OVERRIDE, "override"},
                         {mjENBL_ENERGY, "energy"},
                         {mjENBL_FWDINV, "fwdinv"},
                         {mjENBL_SENSORNOISE, "sensornoise"},
                         {mjENBL_MULTICCD, "multiccd"}};
  for (const Flag& f : enable) {
    if (o.enableflags & f.bit) {
      r.Warn(std::string("<flag ") + f.name +
             "=\"enable\"/> is ignored: it tunes a part of MuJoCo that rigidtouch replaces or "
             "does not have");
    }
  }
  // MuJoCo's solver and integrator: rigidtouch integrates and resolves contact its own way
  std::string tuned;
  auto note = [&tuned](bool differs, const char* attribute) {
    if (differs) tuned += std::string(tuned.empty() ? "" : ", ") + attribute;
  };
  note(o.integrator != def.integrator, "integrator");
  note(o.cone != def.cone, "cone");
  note(o.jacobian != def.jacobian, "jacobian");
  note(o.solver != def.solver, "solver");
  note(o.iterations != def.iterations, "iterations");
  note(o.tolerance != def.tolerance, "tolerance");
  note(o.noslip_iterations != def.noslip_iterations, "noslip_iterations");
  note(o.noslip_tolerance != def.noslip_tolerance, "noslip_tolerance");
  note(o.mpr_iterations != def.mpr_iterations, "mpr_iterations");
  note(o.mpr_tolerance != def.mpr_tolerance, "mpr_tolerance");
  note(o.impratio != def.impratio, "impratio");
  note((o.enableflags & mjENBL_OVERRIDE) &&
           (o.o_margin != def.o_margin || Differs(o.o_solref, def.o_solref, mjNREF) ||
            Differs(o.o_solimp, def.o_solimp, mjNIMP)),
       "o_margin/o_solref/o_solimp");
  if (!tuned.empty()) {
    r.Warn("<option> " + tuned +
           " ignored: they tune MuJoCo's integrator and constraint solver, which rigidtouch "
           "replaces with its own integration and contact (docs/method.md)");
  }
}

void CheckGeoms(const mjModel* m, const Reporter& r) {
  mjtNum def_solref[mjNREF], def_solimp[mjNIMP];
  mj_defaultSolRefImp(def_solref, def_solimp);
  std::string soft, torsional;
  int nsoft = 0, ntorsional = 0;
  for (int g = 0; g < m->ngeom; ++g) {
    const bool tuned = Differs(m->geom_solref + mjNREF * g, def_solref, mjNREF) ||
                       Differs(m->geom_solimp + mjNIMP * g, def_solimp, mjNIMP) ||
                       m->geom_margin[g] != 0.0 || m->geom_gap[g] != 0.0 ||
                       m->geom_solmix[g] != 1.0 || m->geom_priority[g] != 0;
    if (tuned && nsoft++ < 3) soft += (soft.empty() ? "" : ", ") + Name(m, mjOBJ_GEOM, g);
    if (m->geom_condim[g] > 3 && ntorsional++ < 3) {
      torsional += (torsional.empty() ? "" : ", ") + Name(m, mjOBJ_GEOM, g);
    }
  }
  auto more = [](int n) { return n > 3 ? " and " + std::to_string(n - 3) + " more" : ""; };
  if (nsoft > 0) {
    r.Warn("<geom> solref, solimp, margin, gap, solmix or priority set on geom " + soft +
           std::string(more(nsoft)) +
           ": ignored, they tune MuJoCo's soft contact, which rigidtouch replaces with its own "
           "penalty and impulse contact (its stiffness and damping are rigidtouch's settings)");
  }
  if (ntorsional > 0) {
    r.Warn("<geom condim=\"4\" or \"6\"> on geom " + torsional + std::string(more(ntorsional)) +
           ": rigidtouch applies the sliding friction only; torsional and rolling friction are "
           "not simulated");
  }
}

}  // namespace

void CheckElements(const mjModel* m, const std::string& path, std::vector<std::string>& warnings) {
  const Reporter r{path, warnings};
  for (int e = 0; e < m->neq; ++e) {
    r.Refuse(std::string("<equality> <") + EqualityName(m->eq_type[e]) + "> " +
             Name(m, mjOBJ_EQUALITY, e) +
             ": rigidtouch simulates no equality constraints; weld parts by nesting bodies "
             "without a joint instead");
  }
  for (int t = 0; t < m->ntendon; ++t) {
    if (m->tendon_limited[t] || m->tendon_stiffness[t] != 0.0 || m->tendon_damping[t] != 0.0) {
      r.Refuse("<tendon> " + Name(m, mjOBJ_TENDON, t) +
               " has a limit, stiffness or damping: rigidtouch simulates no tendon forces");
    }
  }
  if (m->ntendon > 0) {
    r.Warn("<tendon> " + Name(m, mjOBJ_TENDON, 0) + (m->ntendon > 1 ? " (and others)" : "") +
           " ignored: rigidtouch has no tendons (they exert no force here)");
  }
  for (int d = 0; d < m->nv; ++d) {
    const int j = m->dof_jntid[d];
    if (!io::IsLoneFreeBody(m, m->jnt_bodyid[j]))
      continue;  // a tree's joint: io::CopyTrees honours or refuses these
    if (m->dof_damping[d] != 0.0 || m->dof_armature[d] != 0.0 || m->dof_frictionloss[d] != 0.0 ||
        m->jnt_stiffness[j] != 0.0) {
      r.Refuse("<joint> " + Name(m, mjOBJ_JOINT, m->dof_jntid[d]) +
               " has damping, armature, frictionloss or stiffness: rigidtouch's free bodies move "
               "without joint forces");
    }
  }
  if (m->nsensor > 0) {
    r.Warn("<sensor> " + Name(m, mjOBJ_SENSOR, 0) + (m->nsensor > 1 ? " (and others)" : "") +
           " ignored: rigidtouch computes no MuJoCo sensors");
  }
  CheckOptions(m, r);
  CheckGeoms(m, r);
}

RenderParams SceneRender(const RenderParams& render, double h_s, const std::string& path,
                         std::vector<std::string>& warnings) {
  RenderParams r = render;
  if (r.renderer == RendererKind::kTrain && !r.frequency_given &&
      r.frequency_hz == RenderParams{}.frequency_hz && r.frequency_hz * h_s > 1.0 &&
      std::isfinite(h_s)) {
    r.frequency_hz = 1.0 / h_s;
    std::ostringstream s;
    s << "scene file '" << path << "': its time step h = " << h_s
      << " s is longer than the default train's impulse interval (1 / 250 Hz): the train "
         "frequency is 1/h = "
      << r.frequency_hz << " Hz (one impulse per step); --frequency sets another";
    warnings.push_back(s.str());
  }
  return r;
}

void CheckPairs(const mjModel* m, const std::string& path, std::vector<std::string>& warnings) {
  const Reporter r{path, warnings};
  for (int p = 0; p < m->npair; ++p) {
    const int g1 = m->pair_geom1[p], g2 = m->pair_geom2[p];
    const std::string who = "<contact><pair> " + Name(m, mjOBJ_PAIR, p) + " of geoms " +
                            Name(m, mjOBJ_GEOM, g1) + " and " + Name(m, mjOBJ_GEOM, g2);
    if (!FilterPasses(m, g1, g2)) {
      r.Refuse(who +
               ": rigidtouch collides only the geom pairs MuJoCo's filter allows (contype/"
               "conaffinity bits, different bodies, not a body and its parent unless "
               "filterparent is disabled), and these two are not; make them collide that way and "
               "remove the pair");
    }
    r.Warn(who +
           ": the geoms collide anyway (contype/conaffinity); the pair's condim, friction, "
           "solref, solimp and margin are ignored");
  }
}

// rigidtouch's own collision detection on the initial state (sized from the scene, as the tick's
// is; MuJoCo's mj_collision would need its contact buffer and a stack of nbody^2 / 2 numbers):
// free bodies that start inside each other (or inside a static geom) by more than
// kMaxInitialOverlap are a scene error, since the penalty contact would fling them apart on the
// first tick. Links that start inside static geometry or other links are warned about instead
// (one warning naming three pairs and counting the rest): MuJoCo's articulated models often
// start that way (a root link sunk into the static base it turns on) and MuJoCo collides them
// too, and a refusal would turn those models away
void CheckInitialOverlap(Model& model, const std::string& path) {
  constexpr double kMaxInitialOverlap = 1e-3;  // m, deeper overlaps at start fail
  Data data;
  data.bodies = model.initial;
  data.R_WB.resize(model.bodies.size());
  dynamics::ComputeKinematics(data);
  data.contacts.resize(model.max_contacts);
  data.runs.resize(model.max_contacts);
  geometry::CollisionScratch scratch;
  scratch.Reserve(model);
  geometry::DetectContacts(model, data, scratch);
  std::string links;
  int nlinks = 0;
  const mjModel* m = model.collision.get();
  for (int i = 0; i < data.ncontact; ++i) {
    const Contact& c = data.contacts[i];
    if (!(c.depth_m > kMaxInitialOverlap)) continue;
    // in MuJoCo's geom order, as the message was when MuJoCo's collision made this check
    const int g1 = std::min(c.geom_a, c.geom_b), g2 = std::max(c.geom_a, c.geom_b);
    if (c.body_a < 0 && c.body_b < 0) {  // a link with static geometry or another link
      if (i > 0 && data.contacts[i - 1].geom_a == c.geom_a &&
          data.contacts[i - 1].geom_b == c.geom_b &&
          data.contacts[i - 1].depth_m > kMaxInitialOverlap) {
        continue;  // the pair is named already
      }
      if (++nlinks <= 3) {
        links += std::string(nlinks > 1 ? ", " : "") + GeomName(m, model.geoms[g1]) + " and " +
                 GeomName(m, model.geoms[g2]) + " (" + Num(c.depth_m) + " m)";
      }
      continue;
    }
    throw Error("scene file '" + path + "': geoms " + GeomName(m, model.geoms[g1]) + " and " +
                GeomName(m, model.geoms[g2]) + " overlap by " + Num(c.depth_m) +
                " m at the start (more than " + Num(kMaxInitialOverlap) +
                " m); move them apart in the scene or its keyframe 'initial'");
  }
  if (nlinks > 0) {
    model.load_warnings.push_back(
        "scene file '" + path + "': link geoms overlap at the start by more than " +
        Num(kMaxInitialOverlap) + " m: " + links +
        (nlinks > 3 ? " and " + std::to_string(nlinks - 3) + " more pairs" : "") +
        "; their contacts push them apart from the first step (exclude a pair with <contact>"
        "<exclude>, or contype/conaffinity)");
  }
}

void HonourDisabledConstraints(mjModel* m, const std::string& path, const std::string& tool_name,
                               std::vector<std::string>& warnings) {
  const int flags = m->opt.disableflags & (mjDSBL_CONTACT | mjDSBL_CONSTRAINT);
  if (flags == 0 || tool_name != "none") return;
  for (int b = 1; b < m->nbody; ++b) {
    if (io::IsLoneFreeBody(m, b)) return;  // a free body needs its contacts: refused later
  }
  for (int g = 0; g < m->ngeom; ++g) m->geom_contype[g] = m->geom_conaffinity[g] = 0;
  const bool constraint = (flags & mjDSBL_CONSTRAINT) != 0;
  if (constraint) {
    for (int j = 0; j < m->njnt; ++j) m->jnt_limited[j] = 0;
    for (int d = 0; d < m->nv; ++d) m->dof_frictionloss[d] = 0.0;
  }
  m->opt.disableflags &= ~flags;
  warnings.push_back("scene file '" + path + "': <flag " + (constraint ? "constraint" : "contact") +
                     "=\"disable\"/> honoured as in MuJoCo: no contacts" +
                     (constraint ? ", joint limits or frictionloss" : "") +
                     " in this scene (it has no tool and no free body)");
}

}  // namespace rigidtouch
