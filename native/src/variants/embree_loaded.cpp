// Embree for the Blender extension's module (embree_api.h): the Embree 3 library in the lib/ folder beside the
// module, opened by its path with RTLD_LOCAL and read with dlsym, so that no other Embree in the process (blender.org's
// Blender has Embree 4, with the same function names, in its global scope) can stand in for it. The handle stays open
// for the life of the process, like the Embree device made from it.
#include <dlfcn.h>

#include <stdexcept>
#include <string>

#include "../embree_api.h"

#ifndef PHOTONSPLAT_EMBREE_SONAME
#error "PHOTONSPLAT_EMBREE_SONAME (the file name in lib/, e.g. libembree3.so.3) comes from CMakeLists.txt"
#endif

namespace ps {

namespace {

const int kAnchor = 0;  // an address inside this module, for dladdr

std::string library_path() {
    Dl_info info{};
    if (dladdr(&kAnchor, &info) == 0 || info.dli_fname == nullptr)
        throw std::runtime_error("Embree: cannot tell where the Photon Splat module lies (dladdr failed)");
    const std::string module = info.dli_fname;
    const size_t slash = module.find_last_of('/');
    return (slash == std::string::npos ? std::string() : module.substr(0, slash + 1)) + "lib/" +
           PHOTONSPLAT_EMBREE_SONAME;
}

EmbreeApi load() {
    const std::string path = library_path();
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
        const char* why = dlerror();
        throw std::runtime_error("Embree: cannot load " + path + " (" + (why ? why : "unknown error") +
                                 "); reinstall the Photon Splat extension");
    }
    EmbreeApi api;
    const auto find = [&](const char* name) {
        void* address = dlsym(handle, name);
        if (address == nullptr) throw std::runtime_error("Embree: " + path + " has no function " + name);
        return address;
    };
#define PS_EMBREE_LOOKUP(name) api.name = reinterpret_cast<decltype(api.name)>(find(#name));
    PS_EMBREE_FUNCTIONS(PS_EMBREE_LOOKUP)
#undef PS_EMBREE_LOOKUP
    return api;
}

}  // namespace

const EmbreeApi& embree_api() {
    static const EmbreeApi api = load();
    return api;
}

}  // namespace ps
