// UNTESTED EXAMPLE: written against the OpenHaptics HD API documentation; no SDK or device was
// available, so it was never compiled against the SDK nor run. It uses only the installed
// rigidtouch package (README.md); tests/install compiles and links it against a stub of the HD
// declarations it uses.
//
// Bridges a 3D Systems Touch / Phantom (OpenHaptics HD API) to the rigidtouch UDP device
// protocol, version 3: the HD servo scheduler calls UdpDeviceServer::Step once per servo tick
// (1 kHz), which reads the device, streams its state to the one authenticated renderer, and
// displays that renderer's newest force, clamped to the device's limit.
//
//   openhaptics_bridge [KEY_FILE]
//
// KEY_FILE is the key shared with the renderer (`rigidtouch keygen --out KEY_FILE`, then
// `rigidtouch serve --key KEY_FILE` on the other end); without it, the per-user default key
// (docs/device-protocol.md, "Key files").
#include <HD/hd.h>
#include <rigidtouch/bridge.h>
#include <rigidtouch/device.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <exception>
#include <thread>

namespace {

// set by SIGINT / SIGTERM; a lock-free atomic store is async-signal-safe
std::atomic<bool> g_stop{false};
void OnStopSignal(int) {
  g_stop.store(true);
}

// the HD API's state, in SI units; call only between hdBeginFrame and hdEndFrame
class HdDevice final : public rigidtouch::device::Device {
 public:
  HdDevice() {
    HDdouble max_force_N = 0.0;
    hdGetDoublev(HD_NOMINAL_MAX_CONTINUOUS_FORCE, &max_force_N);
    limits_ = {"openhaptics", max_force_N, 0.0, 0.0};
  }
  rigidtouch::DeviceState Read() override {
    HDdouble transform[16], velocity_mmps[3], angular_radps[3];
    HDint buttons = 0;
    hdGetDoublev(HD_CURRENT_TRANSFORM, transform);  // column-major, translation in mm
    hdGetDoublev(HD_CURRENT_VELOCITY, velocity_mmps);
    hdGetDoublev(HD_CURRENT_ANGULAR_VELOCITY, angular_radps);
    hdGetIntegerv(HD_CURRENT_BUTTONS, &buttons);
    const Eigen::Map<const Eigen::Matrix4d> pose(transform);
    rigidtouch::DeviceState state;
    state.time_s = 1e-9 * static_cast<double>(rigidtouch::device::MonotonicNowNs());
    state.position_m = pose.block<3, 1>(0, 3) * 1e-3;
    state.orientation = rigidtouch::Quat(Eigen::Matrix3d(pose.block<3, 3>(0, 0))).normalized();
    state.velocity_mps = Eigen::Map<const Eigen::Vector3d>(velocity_mmps) * 1e-3;
    state.angular_velocity_radps = Eigen::Map<const Eigen::Vector3d>(angular_radps);
    state.buttons = static_cast<std::uint32_t>(buttons);
    state.valid = !HD_DEVICE_ERROR(hdGetError());
    return state;
  }
  void Write(const rigidtouch::DeviceCommand& command) override {
    // the hardware's own limit, whatever the renderer asked for
    const double norm_N = command.force_N.norm();
    const double scale = norm_N > limits_.max_force_N ? limits_.max_force_N / norm_N : 1.0;
    const Eigen::Vector3d force_N = command.force_N * scale;
    hdSetDoublev(HD_CURRENT_FORCE, force_N.data());
  }
  const rigidtouch::DeviceLimits& limits() const override { return limits_; }

 private:
  rigidtouch::DeviceLimits limits_;
};

HDCallbackCode HDCALLBACK ServoTick(void* server) {
  auto* s = static_cast<rigidtouch::device::UdpDeviceServer*>(server);
  hdBeginFrame(hdGetCurrentDevice());
  if (g_stop.load()) {
    // the last servo tick: zero force, on the servo thread (the device holds its last command)
    s->Release();
    hdEndFrame(hdGetCurrentDevice());
    return HD_CALLBACK_DONE;
  }
  s->Step();
  hdEndFrame(hdGetCurrentDevice());
  return HD_CALLBACK_CONTINUE;
}

}  // namespace

int main(int argc, char** argv) try {
  const HHD handle = hdInitDevice(HD_DEFAULT_DEVICE);
  if (HD_DEVICE_ERROR(hdGetError())) return std::fprintf(stderr, "no HD device\n"), 1;
  hdEnable(HD_FORCE_OUTPUT);
  HdDevice device;
  rigidtouch::device::UdpDeviceServerOptions options;  // udp://127.0.0.1:47000
  if (argc > 1) options.key_file = argv[1];
  // limits() announces the hardware's force limit to the renderer and the server clamps to it
  rigidtouch::device::UdpDeviceServer server(device, options);
  std::signal(SIGINT, OnStopSignal);
  std::signal(SIGTERM, OnStopSignal);
  const HDSchedulerHandle tick =
      hdScheduleAsynchronous(ServoTick, &server, HD_MAX_SCHEDULER_PRIORITY);
  hdStartScheduler();
  while (!g_stop.load()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  std::this_thread::sleep_for(std::chrono::milliseconds(10));  // the servo tick's Release
  hdStopScheduler();
  hdUnschedule(tick);
  hdDisableDevice(handle);
  return 0;
} catch (const std::exception& error) {
  std::fprintf(stderr, "openhaptics bridge: %s\n", error.what());
  return 2;
}
