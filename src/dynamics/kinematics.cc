#include "dynamics/kinematics.h"

namespace rigidtouch::dynamics {

void ComputeKinematics(Data& data) {
  for (std::size_t i = 0; i < data.bodies.size(); ++i) {
    data.R_WB[i] = data.bodies[i].q_WB.toRotationMatrix();
  }
}

}  // namespace rigidtouch::dynamics
