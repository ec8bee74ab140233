// A benchmark engine that simulates nothing: no contacts, every body at the origin, a finite
// state, no warnings. Tests derive from it and override only what they script.
#pragma once

#include <string>
#include <string_view>
#include <utility>

#include "bench/engine.h"

namespace rigidtouch::bench {

class NullEngine : public Engine {
 public:
  explicit NullEngine(std::string name) : name_(std::move(name)) {}
  std::string_view Name() const override { return name_; }
  void Load(const Scene&) override {}
  void Step() override {}
  int ContactCount() const override { return 0; }
  int BodyContactCount(std::string_view) const override { return 0; }
  double DeepestPenetration_m() const override { return 0.0; }
  Vec3 BodyPosition(std::string_view) const override { return Vec3::Zero(); }
  Quat BodyOrientation(std::string_view) const override { return Quat::Identity(); }
  void SetBodyMotion(std::string_view, const Vec3&, const Vec3&) override {}
  void SaveSnapshot() override {}
  void RestoreSnapshot() override {}
  bool StateIsFinite() const override { return true; }
  long WarningCount() const override { return 0; }
  std::string Configuration() const override { return name_; }

 private:
  std::string name_;
};

}  // namespace rigidtouch::bench
