// What every splatting method shares: method names, and the coordinates photons are splatted in.
#include <string>

#include "photonsplat/errors.h"
#include "photonsplat/splat.h"

namespace ps {
namespace {

// Every method and its name; the one list to extend when a method is added.
struct MethodName {
    SplatMethod method;
    const char* name;
};
constexpr MethodName kMethodNames[] = {
    {SplatMethod::brute, "brute"},
    {SplatMethod::cluster, "cluster"},
};

}  // namespace

const char* to_string(SplatMethod method) {
    for (const MethodName& m : kMethodNames)
        if (m.method == method) return m.name;
    return "unknown";
}

SplatMethod splat_method_from_string(const std::string& name) {
    std::string known;
    for (const MethodName& m : kMethodNames) {
        if (name == m.name) return m.method;
        known += known.empty() ? m.name : std::string(", ") + m.name;
    }
    throw InvalidInput("splat method", "'" + name + "' is not one of: " + known);
}

// A float subtraction is already the exactly rounded difference, so doing it in double would not help.
std::vector<glm::vec3> relative_photon_positions(const PhotonMap& photons, const glm::vec3& origin) {
    std::vector<glm::vec3> relative(photons.photons.size());
    for (size_t i = 0; i < relative.size(); ++i) relative[i] = photons.photons[i].position - origin;
    return relative;
}

}  // namespace ps
