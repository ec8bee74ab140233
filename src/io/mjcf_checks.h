// What an MJCF scene asks for that rigidtouch does not simulate: refused with an Error naming the
// element, or accepted with a warning naming it (docs/scenes.md lists which; docs/decisions.md,
// "MJCF coverage", gives the rule). Nothing MuJoCo compiles into the model is ignored silently,
// except what never moves a body (visuals, cameras, lights, sites, sensors' outputs are warned).
#pragma once

#include <mujoco/mujoco.h>

#include <string>
#include <vector>

#include "rigidtouch/model.h"

namespace rigidtouch {

/// Refuses (Error) the elements that change the motion rigidtouch computes: equality constraints,
/// tendons with stiffness, damping or limits, fluid forces, contacts or constraints disabled,
/// contact of predefined pairs only, damping, armature, friction loss or stiffness on a free
/// body's joint (the joints and actuators of articulated trees are io::CopyTrees's).
/// Appends a warning for those that only tune MuJoCo's own solver and soft contact, which
/// rigidtouch replaces with its own (solver options, integrator, solref, solimp, margin, gap,
/// priority, solmix), for torsional and rolling friction (condim 4 and 6), and for sensors and
/// passive tendons.
void CheckElements(const mjModel* m, const std::string& path, std::vector<std::string>& warnings);

/// `<flag contact="disable"/>` or `<flag constraint="disable"/>` in a scene without a tool
/// (`tool_name` "none") and without free bodies: honoured as MuJoCo does, by clearing from the
/// compiled model what rigidtouch would compute (every geom's contype and conaffinity; with
/// `constraint`, every joint's limit and frictionloss too) and then the flag, with a warning
/// saying so. Elsewhere nothing changes (CheckElements then refuses the flag where it matters: a
/// tool or a free body needs contacts).
void HonourDisabledConstraints(mjModel* m, const std::string& path, const std::string& tool_name,
                               std::vector<std::string>& warnings);

/// `render` for a scene stepped at h: the default train frequency (250 Hz, not given by the user)
/// lowered to 1/h with a warning when h is longer than 1/250 s (MuJoCo's humanoid: 5 ms), so
/// that such a scene runs without a flag; everything else as it is (Configure checks it).
RenderParams SceneRender(const RenderParams& render, double h_s, const std::string& path,
                         std::vector<std::string>& warnings);

/// <contact><pair>: refused when the pair would add a contact that MuJoCo's filter excludes (the
/// contype and conaffinity bits, one body after welding, a link and its parent link unless
/// filterparent is disabled: rigidtouch collides only what the filter lets through); otherwise
/// the contact exists anyway and only the pair's parameters are dropped, with a warning.
void CheckPairs(const mjModel* m, const std::string& path, std::vector<std::string>& warnings);

/// The initial state through rigidtouch's own collision detection: a free body inside another
/// geom by more than 1 mm is refused (its penalty contact would fling it on the first step); links
/// inside static geometry or other links by more than that are named in one load warning
/// (MuJoCo's articulated models often start so, and MuJoCo collides them as rigidtouch does).
/// `model` must be configured (its contact capacity sized).
void CheckInitialOverlap(Model& model, const std::string& path);

}  // namespace rigidtouch
