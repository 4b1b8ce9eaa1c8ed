// Multiscatter GGX glass: the random walk of Cycles 3.x on a GGX microsurface, and the tables of what it returns
// (glass_multiscatter.h says what for).
#include "photonsplat/glass_multiscatter.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "photonsplat/closures.h"  // fresnel_dielectric_cos
#include "photonsplat/rng.h"

namespace ps {
namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr int kWalkOrders = 10;  // Cycles' walk gives up after ten scatterings; their light is lost

// ---- The walk (Heitz et al. 2016's microsurface random walk, as Cycles' mf_sample runs it for glass) ------------

// Smith's Λ of isotropic GGX for a direction w (negative below the surface), with Cycles' clamps (mf_lambda).
float smith_lambda(const glm::vec3& w, float alpha) {
    if (w.z > 0.9999f) return 0.0f;
    if (w.z < -0.9999f) return -0.9999f;
    const float inv_z2 = 1.0f / std::max(w.z * w.z, 1e-7f);
    float v = std::sqrt(1.0f + alpha * alpha * (w.x * w.x + w.y * w.y) * inv_z2);
    if (w.z <= 0.0f) v = -v;
    return 0.5f * (v - 1.0f);
}

// The chance that a ray along w at height CDF c1 escapes the microsurface (uniform heights: C1(h) = (h + 1) / 2).
float escape_chance(const glm::vec3& w, float c1, float lambda) {
    if (w.z > 0.9999f) return 1.0f;
    if (w.z < 1e-5f) return 0.0f;
    return std::pow(c1, lambda);
}

// Where a walk travelling along w stands: the height CDF of its last scattering, its Λ and escape chance.
struct WalkState {
    glm::vec3 w{0.0f};
    float c1 = 1.0f;
    float lambda = 0.0f;
    float escape = 0.0f;
};

// Draws the height of the next scattering along s.w; false: the walk leaves the surface (mf_sample_height).
bool next_height(WalkState& s, float u) {
    if (s.w.z > 0.9999f) return false;
    if (s.w.z < -0.9999f) {
        s.c1 *= u;
        s.escape = escape_chance(s.w, s.c1, s.lambda);
    } else if (std::fabs(s.w.z) >= 1e-4f) {
        if (u > 1.0f - s.escape) return false;
        s.c1 = s.lambda >= 0.0f ? 1.0f : s.c1 * std::pow(1.0f - u, -1.0f / s.lambda);
        s.escape = escape_chance(s.w, s.c1, s.lambda);
    }
    return true;
}

// A slope of the unit-roughness GGX visible from a direction of cosine cos_i (Heitz's sampler, Cycles'
// mf_sampleP22_11, its rational fit of the y slope's inverse CDF included).
glm::vec2 visible_unit_slope(float cos_i, float u1, float u2) {
    if (cos_i > 0.9999f || std::fabs(cos_i) < 1e-6f) {
        const float r = std::sqrt(u1 / std::max(1.0f - u1, 1e-7f)), phi = 2.0f * kPi * u2;
        return {r * std::cos(phi), r * std::sin(phi)};
    }
    const float sin_i = std::sqrt(std::max(0.0f, 1.0f - cos_i * cos_i));
    const float tan_i = sin_i / cos_i;
    const float projected = 0.5f * (cos_i + 1.0f);
    if (projected < 1e-4f) return {0.0f, 0.0f};
    const float a = 2.0f * u1 * projected / cos_i - 1.0f;
    float t = a * a - 1.0f;
    if (std::fabs(t) < 1e-7f) return {0.0f, 0.0f};
    t = 1.0f / t;
    const float d = std::sqrt(std::max(0.0f, tan_i * tan_i * t * t - (a * a - tan_i * tan_i) * t));
    const float x_high = tan_i * t + d;
    const float x = (a < 0.0f || x_high > 1.0f / tan_i) ? tan_i * t - d : x_high;
    const float u = u2 >= 0.5f ? 2.0f * (u2 - 0.5f) : 2.0f * (0.5f - u2);
    const float z = (u * (u * (u * 0.27385f - 0.73369f) + 0.46341f)) /
                    (u * (u * (u * 0.093073f + 0.309420f) - 1.0f) + 0.597999f);
    const float y = z * std::sqrt(1.0f + x * x);
    return {x, u2 >= 0.5f ? y : -y};
}

// A microfacet normal visible from w (z may be of either sign: the walk turns its frame over inside the glass).
glm::vec3 visible_normal(const glm::vec3& w, float alpha, float u1, float u2) {
    const glm::vec3 stretched = glm::normalize(glm::vec3(alpha * w.x, alpha * w.y, w.z));
    const glm::vec2 s = visible_unit_slope(stretched.z, u1, u2);
    const float len = std::sqrt(stretched.x * stretched.x + stretched.y * stretched.y);
    const float cos_phi = len > 0.0f ? stretched.x / len : 0.0f, sin_phi = len > 0.0f ? stretched.y / len : 0.0f;
    const float sx = alpha * (cos_phi * s.x - sin_phi * s.y), sy = alpha * (sin_phi * s.x + cos_phi * s.y);
    return glm::normalize(glm::vec3(-sx, -sy, 1.0f));
}

// Reflects (with the dielectric Fresnel of m) or refracts wi, pointing away from the facet, at the facet m.
glm::vec3 scatter_on_facet(const glm::vec3& wi, float eta, const glm::vec3& m, float u, bool& reflected) {
    const float c = glm::dot(wi, m);
    reflected = u < fresnel_dielectric_cos(c, eta);
    if (reflected) return -wi + 2.0f * c * m;
    const float inv = 1.0f / eta;
    const float cos_t = -std::sqrt(std::max(0.0f, 1.0f - (1.0f - c * c) * inv * inv));
    return glm::normalize(m * (c * inv + cos_t) - wi * inv);
}

// One walk entering from wo (z > 0): the number of scatterings before it left (0: it never did, within Cycles'
// ten), whether it left above the surface, and where given, the direction it left along and its throughput (`tint`
// once per scattering after the first). It draws in Cycles' order (the height, the visible normal's y then x, the
// facet's choice), so that on Cycles' own generator it runs on the numbers Cycles' walk does. Uniform: Rng or
// CyclesLcg.
template <class Uniform>
int walk(const glm::vec3& wo, float eta, float alpha, Uniform& rng, bool& above, glm::vec3* direction = nullptr,
         glm::vec3* weight = nullptr, const glm::vec3& tint = glm::vec3(1.0f)) {
    WalkState s;
    s.w = -wo;
    s.lambda = smith_lambda(s.w, alpha);
    bool outside = true;
    glm::vec3 throughput(1.0f);
    for (int order = 0; order < kWalkOrders; ++order) {
        if (!next_height(s, rng.uniform())) {
            above = outside;
            if (direction != nullptr) *direction = outside ? s.w : -s.w;
            if (weight != nullptr) *weight = throughput;
            return order;
        }
        const float uy = rng.uniform(), ux = rng.uniform();
        const glm::vec3 m = visible_normal(-s.w, alpha, ux, uy);
        if (order > 0) throughput *= tint;  // the first scattering's colour is the closure's weight
        bool reflected = false;
        glm::vec3 next = scatter_on_facet(-s.w, outside ? eta : 1.0f / eta, m, rng.uniform(), reflected);
        if (!reflected) {
            // The walk goes on inside: its frame turns over (as Cycles', the height CDF is kept as it was).
            next = -next;
            outside = !outside;
        }
        s.w = next;
        s.lambda = smith_lambda(s.w, alpha);
        s.escape = escape_chance(s.w, s.c1, s.lambda);
    }
    return 0;
}

// ---- Cycles' evaluation towards a light sample (its mf_eval for glass) -------------------------------------------

// GGX's D as Cycles' walk code has it (D_ggx of bsdf_microfacet_multi.h): no test of the side, its density floored.
float walk_d(const glm::vec3& m, float alpha) {
    const float z2 = m.z * m.z, a2 = alpha * alpha, t = (1.0f - z2) + a2 * z2;
    return a2 / std::max(kPi * t * t, 1e-7f);
}

// The light a scattering of a walk travelling along w (its Λ `lambda`) sends towards wo, reflected (wo_outside) or
// refracted into the other side (mf_eval_phase_glass), η seen from w's side.
float phase_towards(const glm::vec3& w, float lambda, const glm::vec3& wo, bool wo_outside, float alpha, float eta) {
    if (w.z > 0.9999f) return 0.0f;
    const float projected = w.z < -0.9999f ? 1.0f : lambda * w.z;
    if (wo_outside) {
        const glm::vec3 h = glm::normalize(wo - w);
        if (h.z < 0.0f) return 0.0f;
        const float c = glm::dot(-w, h);
        return fresnel_dielectric_cos(c, eta) * std::max(0.0f, c) * walk_d(h, alpha) * 0.25f / (projected * c);
    }
    glm::vec3 h = glm::normalize(wo * eta - w);
    if (h.z < 0.0f) h = -h;
    const float c = glm::dot(-w, h), c_o = glm::dot(wo, h);
    if (c < 0.0f) return 0.0f;
    const float t = c + eta * c_o;
    return (1.0f - fresnel_dielectric_cos(c, eta)) * std::max(0.0f, c) * std::max(0.0f, -c_o) * walk_d(h, alpha) /
           (projected * t * t);
}

// One estimate of Cycles' mf_eval (white glass, the tint per scattering after the first) from the view `view`
// towards the light `light`: eval = f |light.z|. Cycles' quirks kept (see the header).
template <class Uniform>
glm::vec3 cycles_glass_eval(float eta, float alpha, const glm::vec3& tint, glm::vec3 view, glm::vec3 light,
                            Uniform& rng) {
    const bool light_outside = light.z >= 0.0f;
    bool swapped = false;
    if (view.z * light.z < 0.0f) {
        if (-light.z < view.z) {  // the light the more grazing: turned round (η kept, as Cycles)
            swapped = true;
            const glm::vec3 t = -light;
            light = -view;
            view = t;
        }
    } else if (light.z < view.z) {
        swapped = true;
        std::swap(view, light);
    }
    if (view.z < 1e-5f || (light.z < 1e-5f && light_outside) || (light.z > -1e-5f && !light_outside))
        return glm::vec3(0.0f);
    WalkState s;
    s.w = -view;
    s.lambda = smith_lambda(s.w, alpha);
    s.c1 = 1.0f;
    s.escape = 0.0f;
    const glm::vec3 towards = light_outside ? light : -light;
    const float shadowing = smith_lambda(towards, alpha);
    // The first scattering, analytic: height-correlated masking of uniform heights on each side.
    float first = phase_towards(s.w, s.lambda, light, light_outside, alpha, eta);
    const float lo = -s.lambda, li = shadowing + 1.0f;
    first *= light_outside ? -s.lambda / (shadowing - s.lambda)
                           : -s.lambda * std::exp(std::lgamma(lo) + std::lgamma(li) - std::lgamma(lo + li));
    glm::vec3 eval(first), throughput(1.0f);
    bool outside = true;
    for (int order = 0; order < kWalkOrders; ++order) {
        if (!next_height(s, rng.uniform())) break;
        const float uy = rng.uniform(), ux = rng.uniform();
        const glm::vec3 m = visible_normal(-s.w, alpha, ux, uy);
        if (order > 0) {
            const float phase = outside ? phase_towards(s.w, s.lambda, light, light_outside, alpha, eta)
                                        : phase_towards(s.w, s.lambda, -light, !light_outside, alpha, 1.0f / eta);
            const float c1 = outside == light_outside ? s.c1 : 1.0f - s.c1;
            eval += throughput * (phase * escape_chance(towards, c1, shadowing));
        }
        if (order + 1 < kWalkOrders) {
            bool reflected = false;
            glm::vec3 next = scatter_on_facet(-s.w, outside ? eta : 1.0f / eta, m, rng.uniform(), reflected);
            if (!reflected) {  // unlike its sampling walk, Cycles' evaluation turns the height over too
                next = -next;
                outside = !outside;
                s.c1 = 1.0f - s.c1;
            }
            s.w = next;
            s.lambda = smith_lambda(s.w, alpha);
            throughput *= tint;
            s.escape = escape_chance(s.w, s.c1, s.lambda);
        }
    }
    if (swapped) eval *= std::fabs(view.z / light.z);
    return eval;
}

// Cycles' fitted albedos of single-scattering GGX (mf_ggx_albedo) and of its transmission
// (mf_ggx_transmission_albedo), which mf_glass_pdf mixes a cosine density in by.
float cycles_ggx_albedo(float r) {
    float albedo = 0.806495f * std::exp(-1.98712f * r * r) + 0.199531f;
    albedo -= ((((((1.76741f * r - 8.43891f) * r + 15.784f) * r - 14.398f) * r + 6.45221f) * r - 1.19722f) * r +
               0.027803f) * r + 0.00568739f;
    return std::clamp(albedo, 0.0f, 1.0f);
}

float cycles_ggx_transmission_albedo(float a, float ior) {
    if (ior < 1.0f) ior = 1.0f / ior;
    a = std::clamp(a, 0.0f, 1.0f);
    ior = std::clamp(ior, 1.0f, 3.0f);
    const float i1 = 0.0476898f * std::exp(-0.978352f * (ior - 0.65657f) * (ior - 0.65657f)) - 0.033756f * ior +
                     0.993261f;
    const float r1 = (((0.116991f * a - 0.270369f) * a + 0.0501366f) * a - 0.00411511f) * a + 1.00008f;
    const float i2 = (((-2.08704f * ior + 26.3298f) * ior - 127.906f) * ior + 292.958f) * ior - 287.946f +
                     199.803f / (ior * ior) - 101.668f / (ior * ior * ior);
    const float r2 = ((((5.3725f * a - 24.9307f) * a + 22.7437f) * a - 3.40751f) * a + 0.0986325f) * a + 0.00493504f;
    return std::clamp(1.0f + i2 * r2 * 0.0019127f - (1.0f - i1) * (1.0f - r1) * 9.3205f, 0.0f, 1.0f);
}

// ---- The first scattering, evaluated ------------------------------------------------------------------------------

// Isotropic GGX's D(h).
float ggx_d(const glm::vec3& h, float alpha) {
    if (!(h.z > 0.0f)) return 0.0f;
    const float a2 = alpha * alpha, t = 1.0f + (a2 - 1.0f) * h.z * h.z;
    return a2 / (kPi * t * t);
}

glm::vec3 direction_of(float cos_o) { return {std::sqrt(std::max(0.0f, 1.0f - cos_o * cos_o)), 0.0f, cos_o}; }

// ---- The tables ---------------------------------------------------------------------------------------------------

// Per (roughness, cos θ_o): the walk's energies, reflect after 1, 2, 3+ scatterings, then transmit likewise, and
// the integrals of multi_ggx_glass_single on the two sides.
constexpr int kRoughnessSteps = 12;  // Blender roughness 0, 1/11, ... 1 (α = roughness²)
constexpr int kCosSteps = 24;        // cos θ_o 0.02, 1/23, ... 0.999: the split between the sides turns sharply
                                     // at the critical angle inside the glass
constexpr int kWalks = 8192;         // per cell: each energy within about 0.5 % of the light
constexpr int kStrata = 64;          // per cell: those integrals from 64 x 64 stratified visible normals
using Cell = std::array<float, 8>;

// ∫ multi_ggx_glass_single cos θ_i dω_i on each side, by the visible normals of wo (stratified).
void single_integrals(float eta, float alpha, float cos_o, float& reflect, float& transmit) {
    const glm::vec3 wo = direction_of(cos_o);
    double r = 0.0, t = 0.0;
    for (int i = 0; i < kStrata; ++i) {
        for (int j = 0; j < kStrata; ++j) {
            const glm::vec3 m = visible_normal(wo, alpha, (float(i) + 0.5f) / kStrata, (float(j) + 0.5f) / kStrata);
            const float c = glm::dot(wo, m);
            if (!(c > 0.0f)) continue;
            const glm::vec3 wr = glm::normalize(2.0f * c * m - wo);
            float pdf = 0.0f;
            const float fr = multi_ggx_glass_single(eta, alpha, wr, wo, &pdf);
            if (wr.z > 0.0f && pdf > 0.0f) r += double(fr) * wr.z / pdf;
            const float sin2_t = (1.0f - c * c) / (eta * eta);
            if (sin2_t >= 1.0f) continue;
            const glm::vec3 wt = glm::normalize(-wo / eta + (c / eta - std::sqrt(1.0f - sin2_t)) * m);
            const float ft = multi_ggx_glass_single(eta, alpha, wt, wo, &pdf);
            if (wt.z < 0.0f && pdf > 0.0f) t += double(ft) * -wt.z / pdf;
        }
    }
    reflect = float(r / (kStrata * kStrata));
    transmit = float(t / (kStrata * kStrata));
}

// At exactly cos θ_o = 1 Cycles' walk sees only the flat microfacet (its visible-normal sampler loses the azimuth
// of a vertical ray), so the last column stops short of it.
float cos_at(int i) { return std::clamp(float(i) / float(kCosSteps - 1), 0.02f, 0.999f); }

class GlassTable {
public:
    explicit GlassTable(float eta) : cells_(kRoughnessSteps * kCosSteps) {
        // Isolated: a render thread may build this under the cache's lock, and must not pick up another task of
        // the render (which could wait for that lock) while its own loop runs.
        tbb::this_task_arena::isolate([&] {
            tbb::parallel_for(tbb::blocked_range<int>(0, kRoughnessSteps * kCosSteps),
                              [&](const tbb::blocked_range<int>& range) {
                                  for (int index = range.begin(); index != range.end(); ++index) build(eta, index);
                              });
        });
    }

    GlassMultiscatterAlbedo lookup(float alpha, float cos_o, const glm::vec3& tint) const {
        const float r = std::clamp(std::sqrt(std::max(alpha, 0.0f)), 0.0f, 1.0f) * float(kRoughnessSteps - 1);
        const float c = std::clamp((std::clamp(cos_o, 0.02f, 0.999f)) * float(kCosSteps - 1), 0.0f,
                                   float(kCosSteps - 1));
        const int r0 = std::min(int(r), kRoughnessSteps - 2), c0 = std::min(int(c), kCosSteps - 2);
        const float fr = std::clamp(r - float(r0), 0.0f, 1.0f), fc = std::clamp(c - float(c0), 0.0f, 1.0f);
        const float weights[4] = {(1 - fr) * (1 - fc), (1 - fr) * fc, fr * (1 - fc), fr * fc};
        const Cell* corners[4] = {&cell(r0, c0), &cell(r0, c0 + 1), &cell(r0 + 1, c0), &cell(r0 + 1, c0 + 1)};
        Cell e{};
        for (int k = 0; k < 4; ++k)
            for (size_t j = 0; j < e.size(); ++j) e[j] += weights[k] * (*corners[k])[j];
        // Each scattering after the first multiplies by the tint: tint^(k−1) after k (tint² for all beyond two).
        const glm::vec3 t = glm::clamp(tint, 0.0f, 1.0f);
        GlassMultiscatterAlbedo out;
        out.single_reflect = e[0];
        out.single_transmit = e[3];
        // The walk's first scattering beyond the evaluated one's integral goes to the cosine lobe, untinted.
        out.multiple_reflect = t * e[1] + t * t * e[2] + std::max(0.0f, e[0] - e[6]);
        out.multiple_transmit = t * e[4] + t * t * e[5] + std::max(0.0f, e[3] - e[7]);
        return out;
    }

private:
    const Cell& cell(int ri, int ci) const { return cells_[size_t(ri * kCosSteps + ci)]; }

    void build(float eta, int index) {
        const int ri = index / kCosSteps, ci = index % kCosSteps;
        const float roughness = float(ri) / float(kRoughnessSteps - 1);
        const float alpha = std::max(roughness * roughness, 1e-4f);  // Cycles' least α, as the walk takes it
        const GlassWalkEnergy e = glass_walk_energy(eta, alpha, cos_at(ci), kWalks, unsigned(index) + 1u);
        Cell& c = cells_[size_t(index)];
        for (int j = 0; j < 3; ++j) {
            c[size_t(j)] = e.reflect[j];
            c[size_t(3 + j)] = e.transmit[j];
        }
        single_integrals(eta, alpha, cos_at(ci), c[6], c[7]);
    }

    std::vector<Cell> cells_;
};

// The tables built so far, by η (to 1/4096); each is built once and never freed, so a pointer stays valid.
const GlassTable& table_for(float eta) {
    static std::mutex mutex;
    static std::map<long, std::unique_ptr<GlassTable>> tables;
    thread_local long last_key = -1;
    thread_local const GlassTable* last = nullptr;
    const long key = std::lround(double(eta) * 4096.0);
    if (last != nullptr && key == last_key) return *last;
    std::lock_guard<std::mutex> lock(mutex);
    auto& slot = tables[key];
    if (!slot) slot = std::make_unique<GlassTable>(float(double(key) / 4096.0));
    last_key = key;
    last = slot.get();
    return *last;
}

}  // namespace

float multi_ggx_glass_single(float eta, float alpha, const glm::vec3& wi, const glm::vec3& wo, float* pdf) {
    if (pdf != nullptr) *pdf = 0.0f;
    if (!(wo.z > 0.0f) || !(alpha > 0.0f)) return 0.0f;
    const float lambda_o = smith_lambda(wo, alpha);
    if (wi.z > 0.0f) {
        const glm::vec3 sum = wi + wo;
        const float len2 = glm::dot(sum, sum);
        if (!(len2 > 1e-12f)) return 0.0f;
        const glm::vec3 h = sum / std::sqrt(len2);
        const float d = ggx_d(h, alpha);
        if (pdf != nullptr) *pdf = d / ((1.0f + lambda_o) * 4.0f * wo.z);
        return fresnel_dielectric_cos(glm::dot(wo, h), eta) * d /
               (4.0f * wo.z * wi.z * (1.0f + lambda_o + smith_lambda(wi, alpha)));
    }
    if (!(wi.z < 0.0f) || std::fabs(eta - 1.0f) < 1e-4f) return 0.0f;
    const glm::vec3 ht = -(wo + eta * wi);
    const float ht2 = glm::dot(ht, ht);
    if (!(ht2 > 1e-12f)) return 0.0f;
    const glm::vec3 h = (eta > 1.0f ? ht : -ht) / std::sqrt(ht2);
    const float cos_oh = glm::dot(wo, h), cos_ih = glm::dot(wi, h);
    if (!(h.z > 0.0f) || !(cos_oh > 0.0f) || !(cos_ih < 0.0f)) return 0.0f;
    const float d = ggx_d(h, alpha);
    const float jacobian = eta * eta * -cos_ih / ht2;  // dω_h / dω_i
    if (pdf != nullptr) *pdf = cos_oh * d / ((1.0f + lambda_o) * wo.z) * jacobian;
    // Transmission's height-correlated masking for uniform heights: B(1 + Λ(wo), 1 + Λ(−wi)) (Cycles' beta()).
    const float lo = 1.0f + lambda_o, li = 1.0f + smith_lambda(-wi, alpha);
    const float masking = std::exp(std::lgamma(lo) + std::lgamma(li) - std::lgamma(lo + li));
    const float denominator = cos_oh + eta * cos_ih;
    // With η², as the GGX refraction's f: what the walk returns. Cycles' mf_eval leaves η² out, and evaluates from
    // the shallower direction with the same η, where it meets a light sample behind the glass (docs/closures.md).
    return (1.0f - fresnel_dielectric_cos(cos_oh, eta)) * eta * eta * cos_oh * -cos_ih * d * masking /
           (wo.z * -wi.z * denominator * denominator);
}

namespace {

// Cycles' light-sample value (f, no cosine) from `walks` of its evaluation walks on `rng`; 0 where Cycles evaluates
// nothing (below α² 1e-7, its sharp glass) or the directions are unusable. α is clamped to 1 as Cycles clamps it.
template <class Uniform>
glm::vec3 light_value_over_walks(float eta, float alpha, const glm::vec3& tint, const glm::vec3& wi,
                                 const glm::vec3& wo, int walks, Uniform& rng) {
    if (!(alpha * alpha >= 1e-7f) || !(eta > 0.0f) || !std::isfinite(eta) || !(walks > 0) || !(wo.z > 0.0f) ||
        !(wi.z != 0.0f))
        return glm::vec3(0.0f);
    const float a = std::min(alpha, 1.0f);
    glm::vec3 sum(0.0f);
    for (int k = 0; k < walks; ++k) sum += cycles_glass_eval(eta, a, glm::clamp(tint, 0.0f, 1.0f), wo, wi, rng);
    const glm::vec3 f = sum / (float(walks) * std::fabs(wi.z));
    return std::isfinite(f.x + f.y + f.z) ? glm::max(f, glm::vec3(0.0f)) : glm::vec3(0.0f);
}

}  // namespace

glm::vec3 cycles3_multi_glass_light_value(float eta, float alpha, const glm::vec3& tint, const glm::vec3& wi,
                                          const glm::vec3& wo, int walks, uint64_t key) {
    Rng rng(key, RngDomain::glass_light_value, 0);
    return light_value_over_walks(eta, alpha, tint, wi, wo, walks, rng);
}

CyclesLcg CyclesLcg::at_vertex(uint32_t path, int vertex) {
    CyclesLcg lcg;
    // lcg_state_init: lcg_init(rng_hash + rng_offset + sample * scramble), rng_offset = 16 (PRNG_BOUNCE_NUM) per
    // surface met, counted from 1; lcg_init steps once.
    lcg.state_ = path + 16u * (uint32_t(vertex) + 1u);
    lcg.state_ = 1103515245u * lcg.state_ + 12345u;
    return lcg;
}

float CyclesLcg::uniform() {
    state_ = 1103515245u * state_ + 12345u;
    return float(state_) * (1.0f / float(0xFFFFFFFFu));
}

glm::vec3 cycles3_multi_glass_light_value(float eta, float alpha, const glm::vec3& tint, const glm::vec3& wi,
                                          const glm::vec3& wo, CyclesLcg& lcg) {
    return light_value_over_walks(eta, alpha, tint, wi, wo, 1, lcg);
}

glm::vec3 cycles3_multi_glass_walk_sample(float eta, float alpha, const glm::vec3& tint, const glm::vec3& wo,
                                          CyclesLcg& lcg, glm::vec3& wi) {
    wi = glm::vec3(0.0f, 0.0f, 1.0f);
    if (!(alpha * alpha >= 1e-7f) || !(eta > 0.0f) || !std::isfinite(eta) || !(wo.z > 0.0f)) return glm::vec3(0.0f);
    bool above = false;
    glm::vec3 weight(0.0f), direction(0.0f);
    const float a = std::clamp(alpha, 1e-4f, 1.0f);
    if (walk(wo, eta, a, lcg, above, &direction, &weight, glm::clamp(tint, 0.0f, 1.0f)) == 0) return glm::vec3(0.0f);
    const float len = glm::length(direction);
    if (!(len > 0.0f) || !std::isfinite(weight.x + weight.y + weight.z)) return glm::vec3(0.0f);
    wi = direction / len;
    return weight;
}

float cycles3_multi_glass_pdf(float eta, float alpha, const glm::vec3& wi, const glm::vec3& wo) {
    // mf_glass_pdf(I = wo, omega_in = wi): Cycles' first argument is the view.
    if (!(alpha * alpha >= 1e-7f) || !(eta > 0.0f) || !std::isfinite(eta)) return 0.0f;
    const float a = std::min(alpha, 1.0f);
    const bool reflective = wo.z * wi.z > 0.0f;
    const glm::vec3 sum = wo + (reflective ? wi : wi * eta);
    const float len = glm::length(sum);
    if (!(len > 0.0f)) return 0.0f;
    glm::vec3 h = sum / len;
    if (h.z < 0.0f) h = -h;
    const glm::vec3 v = wo.z < 0.0f ? -wo : wo;
    const float lambda = smith_lambda(v, a), d = walk_d(h, a);
    const float fresnel = fresnel_dielectric_cos(glm::dot(v, h), eta);
    const float cosine = std::fabs(wi.z) / kPi;
    float pdf;
    if (reflective) {
        const float single = 0.25f * d / std::max((1.0f + lambda) * v.z, 1e-7f);
        const float albedo = cycles_ggx_albedo(a);
        pdf = fresnel * (albedo * single + (1.0f - albedo) * cosine);
    } else {
        const float single = std::fabs(glm::dot(v, h) * glm::dot(wi, h) * d * eta * eta /
                                       std::max((1.0f + lambda) * v.z * len * len, 1e-7f));
        const float albedo = cycles_ggx_transmission_albedo(a, eta);
        pdf = (1.0f - fresnel) * (albedo * single + (1.0f - albedo) * cosine);
    }
    return std::isfinite(pdf) && pdf > 0.0f ? pdf : 0.0f;
}

GlassWalkEnergy glass_walk_energy(float eta, float alpha, float cos_o, int walks, unsigned seed) {
    GlassWalkEnergy out;
    if (!(walks > 0) || !(eta > 0.0f) || !std::isfinite(eta)) return out;
    Rng rng(seed, RngDomain::glass_walk, 0x77616c6bull);
    const glm::vec3 wo = direction_of(std::clamp(cos_o, 1e-4f, 1.0f));
    const float a = std::clamp(alpha, 1e-4f, 1.0f);  // Cycles' clamp of the walk's α
    double reflect[3] = {0, 0, 0}, transmit[3] = {0, 0, 0};
    for (int k = 0; k < walks; ++k) {
        bool above = false;
        const int scatterings = walk(wo, eta, a, rng, above);
        if (scatterings == 0) continue;
        double* side = above ? reflect : transmit;
        side[std::min(scatterings, 3) - 1] += 1.0;
    }
    for (int j = 0; j < 3; ++j) {
        out.reflect[j] = float(reflect[j] / walks);
        out.transmit[j] = float(transmit[j] / walks);
    }
    return out;
}

GlassMultiscatterAlbedo glass_multiscatter_albedo(float eta, float alpha, float cos_o, const glm::vec3& tint) {
    if (!(cos_o > 0.0f) || !(eta > 0.0f) || !std::isfinite(eta) || !std::isfinite(alpha)) return {};
    return table_for(eta).lookup(alpha, cos_o, tint);
}

}  // namespace ps
