// STUB FOR COMPILE CHECKS ONLY, not the OpenHaptics SDK: the few HD API declarations that
// examples/vendor_bridge/openhaptics_bridge.cc uses, written by hand from the SDK's documentation
// so the install test can compile and link the bridge without the SDK. Names and signatures
// follow the HD API; the numeric values are placeholders, and every function is an inline no-op
// (getters return zeros, hdGetError reports success). Never run a program built against it.
#pragma once

typedef unsigned int HHD;
typedef unsigned int HDenum;
typedef unsigned int HDerror;
typedef int HDint;
typedef double HDdouble;
typedef unsigned short HDushort;
typedef const char* HDstring;
typedef unsigned int HDCallbackCode;
typedef unsigned long HDSchedulerHandle;

#define HDCALLBACK
typedef HDCallbackCode(HDCALLBACK* HDSchedulerCallback)(void* pUserData);

#define HD_CALLBACK_DONE 0
#define HD_CALLBACK_CONTINUE 1
#define HD_DEFAULT_DEVICE ((HDstring)0)
#define HD_MAX_SCHEDULER_PRIORITY 0xffff
#define HD_SUCCESS 0x0000

// placeholder values: only the names matter to a compile check
#define HD_CURRENT_BUTTONS 0x2000
#define HD_CURRENT_VELOCITY 0x2001
#define HD_CURRENT_TRANSFORM 0x2002
#define HD_CURRENT_ANGULAR_VELOCITY 0x2003
#define HD_NOMINAL_MAX_CONTINUOUS_FORCE 0x2004
#define HD_CURRENT_FORCE 0x2005
#define HD_FORCE_OUTPUT 0x4000

typedef struct {
  HDerror errorCode;
  int internalErrorCode;
  HHD hHD;
} HDErrorInfo;
#define HD_DEVICE_ERROR(X) (((X).errorCode) != HD_SUCCESS)

inline HHD hdInitDevice(HDstring) {
  return 0;
}
inline void hdDisableDevice(HHD) {}
inline HHD hdGetCurrentDevice() {
  return 0;
}
inline void hdBeginFrame(HHD) {}
inline void hdEndFrame(HHD) {}
inline HDErrorInfo hdGetError() {
  return HDErrorInfo{HD_SUCCESS, 0, 0};
}
inline void hdEnable(HDenum) {}
inline void hdGetDoublev(HDenum, HDdouble* params) {
  params[0] = 0.0;
}
inline void hdGetIntegerv(HDenum, HDint* params) {
  params[0] = 0;
}
inline void hdSetDoublev(HDenum, const HDdouble*) {}
inline HDSchedulerHandle hdScheduleAsynchronous(HDSchedulerCallback, void*, HDushort) {
  return 0;
}
inline void hdUnschedule(HDSchedulerHandle) {}
inline void hdStartScheduler() {}
inline void hdStopScheduler() {}
