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
    // The path scattered off a glossy, mirror or refracting part (not diffuse, translucent or transparent) and then
    // reached a diffuse part (a later diffuse bounce, or this surface's own diffuse reflection): the light that
    // Cycles' Caustics toggles (Light Paths) remove, and the engine's Caustics pass.
    kGlossyPath = 4u,
};

struct Photon {
    glm::vec3 position;  // world space
    glm::vec3 wi;        // unit, pointing back towards where the photon came from
    glm::vec3 normal;    // geometric normal at the hit, flipped so that dot(normal, wi) > 0
    glm::vec3 power;     // flux [W] carried; the estimate divides by the number of EMITTED photons
    uint32_t flags;      // PhotonFlags
};

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
    // What the camera sees (render space; radius 0: unknown): a programmed world sends half of its photons
    // through it (world.h).
    glm::vec3 focus_center{0.0f};
    float focus_radius = 0.0f;
};

PhotonMap trace_photons(const Scene& scene, const PhotonSettings& settings, const RenderControl& control,
                        Stats& stats);

}  // namespace ps
