#include "photonsplat/settings.h"

#include <cmath>
#include <string>

#include "photonsplat/errors.h"

namespace ps {

namespace {

constexpr uint64_t kMaxPhotons = 500'000'000;  // ~40 GB of photon records: beyond any machine we target
constexpr uint32_t kMaxPasses = 1'000'000;      // r shrinks as passes^(−1/6): far past any useful radius
constexpr double kMaxTimeLimit = 1e7;           // seconds, about 4 months

template <typename T>
void require(bool ok, const std::string& field, const std::string& what, T value) {
    if (!ok) throw InvalidInput(field, what + ", got " + std::to_string(value));
}

}  // namespace

void validate(const RenderSettings& s) {
    require(s.photons <= kMaxPhotons, "photons", "must be at most " + std::to_string(kMaxPhotons), s.photons);
    require(std::isfinite(s.radius) && s.radius >= 0.0f, "radius", "must be finite and >= 0 (0 = automatic)", s.radius);
    require(s.max_bounces >= 0 && s.max_bounces <= 1000, "max_bounces", "must be in [0, 1000]", s.max_bounces);
    require(s.threads >= 0 && s.threads <= 4096, "threads", "must be in [0, 4096] (0 = all cores)", s.threads);
    require(s.direct_samples >= 1 && s.direct_samples <= 4096, "direct_samples", "must be in [1, 4096]",
            s.direct_samples);
    require(std::isfinite(s.normal_tolerance) && s.normal_tolerance > 0.0f && s.normal_tolerance <= 180.0f,
            "normal_tolerance", "must be in (0, 180] degrees", s.normal_tolerance);
    require(std::isfinite(s.plane_distance) && s.plane_distance >= 0.0f, "plane_distance",
            "must be finite and >= 0 (0 = off)", s.plane_distance);
    require(s.directional_level >= -1 && s.directional_level <= 64, "directional_level",
            "must be in [-1, 64] (-1 = chosen from the radius)", s.directional_level);
    require(s.iterations <= kMaxPasses, "passes", "must be in [0, " + std::to_string(kMaxPasses) + "] (0 = until time_limit)",
            s.iterations);
    require(std::isfinite(s.time_limit) && s.time_limit >= 0.0 && s.time_limit <= kMaxTimeLimit, "time_limit",
            "must be in [0, " + std::to_string(int(kMaxTimeLimit)) + "] seconds (0 = none)", s.time_limit);
    require(s.iterations > 0 || s.time_limit > 0.0, "passes",
            "0 (no pass limit) needs a time_limit > 0, else the render would never end", s.iterations);
    require(std::isfinite(s.aimed_photons) && s.aimed_photons >= 0.0f && s.aimed_photons <= 16.0f, "aimed_photons",
            "must be in [0, 16] (a fraction of photons; 0 = off)", s.aimed_photons);
    require((s.outputs & ~kAllFilmOutputs) == 0, "outputs", "names an output that does not exist", s.outputs);
    require(std::isfinite(s.alpha) && s.alpha > 0.0f && s.alpha <= 1.0f, "alpha",
            "must be in (0, 1] (2/3 balances noise and blur; 1 keeps the radius fixed)", s.alpha);
}

FilmOutputSet requested_outputs(const RenderSettings& settings) {
    FilmOutputSet outputs = (settings.outputs & kAllFilmOutputs) | film_bit(FilmOutput::combined);
    if (settings.caustics_pass) outputs |= film_bit(FilmOutput::caustics);
    return outputs;
}

}  // namespace ps
