// The Embree functions the core calls, reached through one table (embree_api()) instead of the dynamic linker's
// symbol lookup.
//
// Why: blender.org's Blender 4.x links Embree 4 into the blender program, and Embree 4 exports the same function
// names as Embree 3 (rtcNewDevice, rtcIntersect1...). The program's libraries form the process's global symbol
// scope, which the loader searches before the libraries a Python module brought with it: a module linked to Embree 3
// the ordinary way has its calls bound to Embree 4, which reads Embree 3's structures wrongly and crashes (as other
// render add-ons did; tests/blender/test_extension.py reproduces it). Two providers of the table, one per module
// variant (src/variants/):
//   embree_linked.cpp  the addresses the static linker resolved: the build against Debian's libraries, whose Blender
//                      (3.4) links the very same Embree 3, so there is nothing to clash with;
//   embree_loaded.cpp  dlsym on the extension's own Embree 3, opened by path from the lib/ folder beside the module
//                      with RTLD_LOCAL: a lookup on that handle searches that library only, never the global scope.
#pragma once
#include <embree3/rtcore.h>

// Every Embree function the core calls (rtcInitIntersectContext is inline in the header: not a symbol).
#define PS_EMBREE_FUNCTIONS(X)                                                                               \
    X(rtcNewDevice) X(rtcGetDeviceError) X(rtcNewScene) X(rtcSetSceneFlags) X(rtcCommitScene)               \
    X(rtcReleaseScene) X(rtcRetainScene) X(rtcGetSceneBounds) X(rtcNewGeometry)                             \
    X(rtcSetSharedGeometryBuffer) X(rtcSetNewGeometryBuffer)                                                \
    X(rtcSetGeometryMask) X(rtcSetGeometryInstancedScene) X(rtcSetGeometryTimeStepCount)                   \
    X(rtcSetGeometryTransform) X(rtcCommitGeometry) X(rtcAttachGeometryByID) X(rtcReleaseGeometry)         \
    X(rtcEnableGeometry) X(rtcDisableGeometry) X(rtcIntersect1) X(rtcOccluded1) X(rtcUpdateGeometryBuffer)   \
    X(rtcIntersect8) X(rtcOccluded8) X(rtcDetachGeometry)

namespace ps {

struct EmbreeApi {
#define PS_EMBREE_POINTER(name) decltype(&::name) name = nullptr;
    PS_EMBREE_FUNCTIONS(PS_EMBREE_POINTER)
#undef PS_EMBREE_POINTER
};

// The table, filled on first use; throws std::runtime_error saying why when Embree cannot be loaded.
const EmbreeApi& embree_api();

}  // namespace ps
