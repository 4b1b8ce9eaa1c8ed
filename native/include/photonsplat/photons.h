// Stage 4 of the pipeline: photons traced from the lights with Embree and stored at non-specular hits after
// at least one bounce (direct light is computed separately by shadow rays, so first hits would count twice).
#pragma once
#include <cstdint>
#include <vector>

#include <glm/vec3.hpp>

namespace ps {

class Scene;
class RenderControl;
struct Stats;

enum PhotonFlags : uint32_t {
    kCaustic = 1u,  // path light → specular+ → this diffuse hit (L S+ D)
    kInsidePhoton = 2u,  // stored on the back face of a transmitting surface (inside glass): splats only onto view
                         // samples there too, never through the surface onto what lies close outside (splat.h)
    // A caustic photon stored on a translucent surface: the far sides of that surface's view samples gather it
    // (ViewSamples::far_side, render.cpp).
    kFarSidePhoton = 4u,
    kFarSideOnly = 8u,  // ... and that surface reflects nothing: only they do, the splat of the view samples never
    // Its last scatter (transparency aside) was a glossy, mirror or refracting part: light such parts may have
    // focused. Only these can take a smaller radius (photon_density.h).
    kAfterGlossy = 16u,
};

// The share of a photon's light that Cycles' Caustics toggles (Light Paths, reflective and refractive off) remove,
// in 1/65535: the engine's Caustics output (render.cpp). The toggles drop every glossy, mirror or refracting part
// met right after a scatter Cycles labelled diffuse, and Cycles labels a scatter by the part its camera path
// picked to sample it (shading.h: ScatterLabel, LabelShare). So what they remove of a photon's light depends on
// how the camera path reaches the surface that stores it: by a scatter not labelled diffuse (the camera's own ray,
// a mirror, glass), or by one labelled diffuse (then that surface's own glossy and refracting parts go too).
enum CausticState : int { kReachedOtherwise = 0, kReachedDiffusely = 1 };
constexpr float kCausticShareUnit = 65535.0f;

struct Photon {
    glm::vec3 position;  // world space
    glm::vec3 wi;        // unit, pointing back towards where the photon came from
    glm::vec3 normal;    // geometric normal at the hit, flipped so that dot(normal, wi) > 0
    glm::vec3 power;     // flux [W] carried; the estimate divides by the number of EMITTED photons
    uint32_t flags;      // PhotonFlags
    // The share removed by the Caustics toggles, by CausticState and channel (0: none, light that met diffuse
    // parts only).
    uint16_t caustic_share[2][3];
};
inline glm::vec3 caustic_share(const Photon& p, CausticState state) {
    const uint16_t* s = p.caustic_share[state];
    return glm::vec3(s[0], s[1], s[2]) / kCausticShareUnit;
}

struct PhotonMap {
    std::vector<Photon> photons;  // in Morton order of position, ties by emission order: deterministic
    uint64_t emitted = 0;         // ordinary photon paths started: the density estimate divides by this
    uint64_t aimed = 0;           // extra caustic photon paths aimed at mirrors and glass (caustic_aim.h)
    size_t bytes() const { return photons.capacity() * sizeof(Photon); }
};

struct PhotonSettings {
    uint64_t count = 0;       // photon paths to emit
    int max_bounces = 8;      // path length bound (a photon is stored at most this many times)
    uint64_t seed = 0;
    bool guide = true;        // learn where sun photons get stored, and emit them there (emission_guide.h)
    float aimed_fraction = 0.0f;  // extra photons aimed at mirrors and glass, × count (caustic_aim.h); 0 = off
    bool caustic_shares = false;  // fill Photon::caustic_share (a Caustics output needs it); else it stays 0
    // What the camera sees (render space; radius 0: unknown): a programmed world sends half of its photons
    // through it (world.h).
    glm::vec3 focus_center{0.0f};
    float focus_radius = 0.0f;
};

PhotonMap trace_photons(const Scene& scene, const PhotonSettings& settings, const RenderControl& control,
                        Stats& stats);

}  // namespace ps
