#include "photonsplat/closures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "photonsplat/brdf.h"
#include "photonsplat/errors.h"
#include "photonsplat/glass_multiscatter.h"
#include "photonsplat/validation.h"

// Every lobe is evaluated in a local frame (x, y, n): the microfacet formulas then read as in the papers, and the
// anisotropic ones need only the frame's x along the tangent. docs/closures.md lists, per closure, the Cycles 3.4
// function it follows and what differs.

namespace ps {

namespace {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.318309886183790671538f;
constexpr float kTwoPi = 6.28318530717958647692f;

// Cycles treats a microfacet lobe with α_x α_y at or below this as a delta (its eval returns 0 there); so do we.
constexpr float kSingularAlphaProduct = 1e-7f;
// Cycles' Beckmann and GGX refraction are singular at |η − 1| < 1e-4 (the light goes straight through).
constexpr float kSingularEta = 1e-4f;
// Cycles' clearcoat masks with GGX at a fixed α (bsdf_microfacet.h: "alpha2 = 0.0625").
constexpr float kClearcoatMaskingAlpha = 0.25f;

// Cycles' sampling weight of a closure of this weight (closure/alloc.h): |the mean of its channels|.
float sampling_weight_of(const glm::vec3& c) { return std::fabs((c.x + c.y + c.z) * (1.0f / 3.0f)); }

float pow5(float m) {
    const float m2 = m * m;
    return m2 * m2 * m;
}
// Cycles' schlick_fresnel: (1 − u)^5 with u clamped.
float schlick_weight(float u) { return pow5(std::clamp(1.0f - u, 0.0f, 1.0f)); }

bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

struct Frame {
    glm::vec3 x, y, z;
    glm::vec3 to_local(const glm::vec3& v) const { return {glm::dot(v, x), glm::dot(v, y), glm::dot(v, z)}; }
    glm::vec3 to_world(const glm::vec3& v) const { return v.x * x + v.y * y + v.z * z; }
};

// Any orthonormal frame around n (Duff et al. 2017, as scattering.cpp's orthonormal_basis).
Frame basis_around(const glm::vec3& n) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float b = n.x * n.y * a;
    return {glm::vec3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x), glm::vec3(b, sign + n.y * n.y * a, -n.y),
            n};
}

// The lobe's frame: around n, with x along the tangent projected onto the surface and y = n × x where the lobe is
// anisotropic (Cycles' make_orthonormals_tangent). False where an anisotropic lobe has no usable tangent.
bool lobe_frame(const Lobe& lobe, const glm::vec3& n, Frame& frame) {
    const bool anisotropic = (lobe.kind == ClosureKind::reflection || lobe.kind == ClosureKind::refraction) &&
                             lobe.distribution != Distribution::gtr1 &&
                             lobe.distribution != Distribution::multi_ggx_glass && lobe.alpha_x != lobe.alpha_y;
    if (!anisotropic) {
        frame = basis_around(n);
        return true;
    }
    const glm::vec3 t = lobe.tangent - n * glm::dot(n, lobe.tangent);
    const float len2 = glm::dot(t, t);
    if (!(len2 > 1e-12f) || !std::isfinite(len2)) return false;
    frame.x = t / std::sqrt(len2);
    frame.y = glm::cross(n, frame.x);
    frame.z = n;
    return true;
}

glm::vec3 cosine_hemisphere_local(float u1, float u2) {
    const float r = std::sqrt(u1), phi = kTwoPi * u2;
    return {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1.0f - u1))};
}

// ---- Microfacet distributions, in the local frame (h.z = cos θ_h) ----------------------------------------------

struct Alphas {
    float x, y;
};
// The lobe's α, clamped as Cycles' setup does (to [0, 1]) and away from zero for float; false where Cycles would
// treat the lobe as a delta.
bool lobe_alphas(const Lobe& lobe, Alphas& a) {
    float ax = lobe.alpha_x, ay = lobe.alpha_y;
    // Cycles' clearcoat is isotropic, and so is its Multiscatter GGX Glass (α_y = α_x)
    if (lobe.distribution == Distribution::gtr1 || lobe.distribution == Distribution::multi_ggx_glass) ay = ax;
    if (!(ax * ay > kSingularAlphaProduct)) return false;
    a.x = std::clamp(ax, kMinGgxAlpha, 1.0f);
    a.y = std::clamp(ay, kMinGgxAlpha, 1.0f);
    return true;
}

// (α_x² v_x² + α_y² v_y²) / v_z²: the α² tan²θ of a direction, which both Smith terms depend on.
float alpha2_tan2(const glm::vec3& v, Alphas a) {
    return (a.x * a.x * v.x * v.x + a.y * a.y * v.y * v.y) / (v.z * v.z);
}

float ggx_d(const glm::vec3& h, Alphas a) {
    if (!(h.z > 0.0f)) return 0.0f;
    const float t = h.x * h.x / (a.x * a.x) + h.y * h.y / (a.y * a.y) + h.z * h.z;
    return kInvPi / (a.x * a.y * t * t);
}

// Smith G1 of GGX; v on either side (Cycles squares the cosine).
float ggx_g1(const glm::vec3& v, Alphas a) {
    if (v.z == 0.0f) return 0.0f;
    return 2.0f / (1.0f + std::sqrt(1.0f + alpha2_tan2(v, a)));
}

// Smith's Λ of GGX (Cycles' mf_lambda for a direction above the surface): G1 = 1 / (1 + Λ).
float ggx_lambda(const glm::vec3& v, Alphas a) {
    return 0.5f * (std::sqrt(1.0f + alpha2_tan2(v, a)) - 1.0f);
}

// The height-correlated Smith masking-shadowing of GGX, G2 = 1 / (1 + Λ(wo) + Λ(wi)): Cycles' multiscatter GGX's
// single scattering (G2 in mf_eval_glossy), where plain GGX uses the separable G1(wo) G1(wi).
float ggx_g2_correlated(const glm::vec3& wo, const glm::vec3& wi, Alphas a) {
    if (wo.z == 0.0f || wi.z == 0.0f) return 0.0f;
    return 1.0f / (1.0f + ggx_lambda(wo, a) + ggx_lambda(wi, a));
}

float beckmann_d(const glm::vec3& h, Alphas a) {
    if (!(h.z > 0.0f)) return 0.0f;
    const float cos2 = h.z * h.z;
    const float e = (h.x * h.x / (a.x * a.x) + h.y * h.y / (a.y * a.y)) / cos2;
    return std::exp(-e) * kInvPi / (a.x * a.y * cos2 * cos2);
}

// Cycles' rational approximation of Beckmann's Smith G1 (bsdf_beckmann_G1 / bsdf_beckmann_aniso_G1).
float beckmann_g1(const glm::vec3& v, Alphas a) {
    if (v.z == 0.0f) return 0.0f;
    const float inv_a = std::sqrt(alpha2_tan2(v, a));
    if (inv_a < 0.625f) return 1.0f;
    const float k = 1.0f / inv_a;
    return ((2.181f * k + 3.535f) * k) / ((2.577f * k + 2.276f) * k + 1.0f);
}

// Cycles' D_GTR1 (Burley's clearcoat distribution), normalised so ∫ D cos θ_h dω = 1.
float gtr1_d(float cos_h, float alpha) {
    if (!(cos_h > 0.0f)) return 0.0f;
    if (alpha >= 1.0f) return kInvPi;
    const float a2 = alpha * alpha;
    const float t = 1.0f + (a2 - 1.0f) * cos_h * cos_h;
    return (a2 - 1.0f) / (kPi * std::log(a2) * t);
}

// GGX visible normals of wo (Heitz 2018), anisotropic: density G1(wo) max(0, wo·h) D(h) / wo.z.
glm::vec3 sample_ggx_visible_normal(const glm::vec3& wo, Alphas a, float u1, float u2) {
    const glm::vec3 v = glm::normalize(glm::vec3(a.x * wo.x, a.y * wo.y, wo.z));
    const float len2 = v.x * v.x + v.y * v.y;
    const glm::vec3 b1 = len2 > 1e-14f ? glm::vec3(-v.y, v.x, 0.0f) / std::sqrt(len2) : glm::vec3(1.0f, 0.0f, 0.0f);
    const glm::vec3 b2 = glm::cross(v, b1);
    const float r = std::sqrt(u1), phi = kTwoPi * u2;
    const float p1 = r * std::cos(phi);
    const float s = 0.5f * (1.0f + v.z);
    const float p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * r * std::sin(phi);
    const glm::vec3 hs = p1 * b1 + p2 * b2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * v;
    return glm::normalize(glm::vec3(a.x * hs.x, a.y * hs.y, std::max(hs.z, 1e-6f)));
}

// Beckmann normals with density D(h) cos θ_h: Gaussian slopes with deviation α/√2 per axis.
glm::vec3 sample_beckmann_normal(Alphas a, float u1, float u2) {
    const float r = std::sqrt(-std::log1p(-u1)), phi = kTwoPi * u2;
    return glm::normalize(glm::vec3(-a.x * r * std::cos(phi), -a.y * r * std::sin(phi), 1.0f));
}

// ---- Fresnel -----------------------------------------------------------------------------------------------------

glm::vec3 fresnel_color(FresnelKind kind, const glm::vec3& specular_color, float eta, float cos_theta) {
    switch (kind) {
        case FresnelKind::none: return glm::vec3(1.0f);
        case FresnelKind::principled: {
            // Cycles' interpolate_fresnel_color: the dielectric curve rescaled to run from cspec0 to 1.
            const glm::vec3 cspec0 = glm::clamp(specular_color, 0.0f, 1.0f);
            const float f0 = fresnel_dielectric_cos(1.0f, eta);
            const float fh = f0 < 1.0f ? (fresnel_dielectric_cos(cos_theta, eta) - f0) / (1.0f - f0) : 1.0f;
            return cspec0 * (1.0f - fh) + glm::vec3(fh);
        }
        case FresnelKind::dielectric: return glm::vec3(fresnel_dielectric_cos(cos_theta, eta));
        case FresnelKind::schlick: return fresnel_schlick(glm::clamp(specular_color, 0.0f, 1.0f), cos_theta);
    }
    return glm::vec3(1.0f);
}

// The hemispherical average 2∫F(μ)μ dμ of the dielectric Fresnel (Kulla & Conty 2017's fit).
float dielectric_fresnel_average(float eta) {
    if (eta >= 1.0f) return (eta - 1.0f) / (4.08567f + 1.00071f * eta);
    return std::clamp(0.997118f + eta * (0.1014f + eta * (-0.965241f - 0.130607f * eta)), 0.0f, 1.0f);
}

glm::vec3 fresnel_average(FresnelKind kind, const glm::vec3& specular_color, float eta) {
    switch (kind) {
        case FresnelKind::none: return glm::vec3(1.0f);
        case FresnelKind::principled: {
            const glm::vec3 cspec0 = glm::clamp(specular_color, 0.0f, 1.0f);
            const float f0 = fresnel_dielectric_cos(1.0f, eta);
            const float fh = f0 < 1.0f ? (dielectric_fresnel_average(eta) - f0) / (1.0f - f0) : 1.0f;
            return cspec0 * (1.0f - fh) + glm::vec3(fh);
        }
        case FresnelKind::dielectric: return glm::vec3(dielectric_fresnel_average(eta));
        case FresnelKind::schlick: {
            const glm::vec3 f0 = glm::clamp(specular_color, 0.0f, 1.0f);
            return f0 + (glm::vec3(1.0f) - f0) * (1.0f / 21.0f);  // 2∫(1 − μ)^5 μ dμ = 1/21
        }
    }
    return glm::vec3(1.0f);
}

// ---- Multiple-scattering compensation of GGX (Kulla & Conty 2017) -----------------------------------------------
//
// E(μ, α) = ∫ f_ss(wi, wo) cos θ_i dwi for white single-scatter multi_ggx (GGX with the height-correlated G2, as
// Cycles' multiscatter GGX scatters once), μ = cos θ_o: the energy one bounce keeps. The light the microsurface
// scatters more than once, 1 − E(μ_o), leaves with the lobe
//   f_ms(wi, wo) = (1 − E(μ_o)) (1 − E(μ_i)) / (π (1 − E_avg(α))) · T,   E_avg = 2∫E(μ)μ dμ,
// whose albedo is exactly 1 − E(μ_o) for T = 1: single + multiple scattering reflect all the light for F = 1.
// T is the colour those extra bounces keep (multi_scatter).

// The escape-rate profile s(μ) = √μ of the coloured compensation (multi_scatter) and its slope in α.
constexpr float kMultiTintSlope = 0.43f;
float multi_tint_profile(float mu) { return std::sqrt(std::max(mu, 0.0f)); }

class GgxAlbedoTable {
public:
    static constexpr int kMu = 32, kAlpha = 32;

    GgxAlbedoTable() {
        constexpr int kStrata = 32;  // a fixed 32×32 stratified grid of visible normals per entry: no randomness
        for (int j = 0; j < kAlpha; ++j) {
            const float alpha = std::max(j / float(kAlpha - 1), kMinGgxAlpha);
            const Alphas a{alpha, alpha};
            for (int i = 0; i < kMu; ++i) {
                const float mu = std::max(i / float(kMu - 1), 1e-3f);
                const glm::vec3 wo(std::sqrt(1.0f - mu * mu), 0.0f, mu);
                const float lambda_o = ggx_lambda(wo, a);
                double sum = 0.0;
                for (int s1 = 0; s1 < kStrata; ++s1)
                    for (int s2 = 0; s2 < kStrata; ++s2) {
                        const glm::vec3 h = sample_ggx_visible_normal(wo, a, (s1 + 0.5f) / kStrata,
                                                                      (s2 + 0.5f) / kStrata);
                        const float c = glm::dot(wo, h);
                        if (!(c > 0.0f)) continue;
                        const glm::vec3 wi = 2.0f * c * h - wo;
                        // f cos / pdf under visible-normal sampling: G2(wo, wi) / G1(wo)
                        if (wi.z > 0.0f) sum += (1.0f + lambda_o) / (1.0f + lambda_o + ggx_lambda(wi, a));
                    }
                e_[j][i] = std::min(1.0f, float(sum / (kStrata * kStrata)));
            }
            // E_avg = 2∫E(μ)μ dμ of the piecewise-linear E, integrated exactly, so that f_ms integrates to
            // 1 − E(μ_o) for the interpolated E the lobe uses.
            double avg = 0.0;
            for (int i = 0; i + 1 < kMu; ++i) {
                const double m0 = i / double(kMu - 1), m1 = (i + 1) / double(kMu - 1), h = m1 - m0;
                const double e0 = e_[j][i], e1 = e_[j][i + 1];
                avg += 2.0 * h * (e0 * (m0 / 2.0 + h / 6.0) + e1 * (m0 / 2.0 + h / 3.0));
            }
            avg_[j] = float(avg);
            // The mean of s(μ_i) over the compensation lobe's directions (weight (1 − E(μ_i)) μ_i), midpoint rule.
            constexpr int kSteps = 256;
            double num = 0.0, den = 0.0;
            for (int k = 0; k < kSteps; ++k) {
                const double m = (k + 0.5) / kSteps;
                const double fm = m * (kMu - 1);
                const int i = std::min(int(fm), kMu - 2);
                const double e = e_[j][i] + (e_[j][i + 1] - e_[j][i]) * (fm - i);
                const double w = (1.0 - e) * m;
                num += w * multi_tint_profile(float(m));
                den += w;
            }
            profile_mean_[j] = den > 0.0 ? float(num / den) : multi_tint_profile(0.5f);
        }
    }

    float albedo(float mu, float alpha) const {
        const float fm = std::clamp(mu, 0.0f, 1.0f) * (kMu - 1), fa = std::clamp(alpha, 0.0f, 1.0f) * (kAlpha - 1);
        const int i = std::min(int(fm), kMu - 2), j = std::min(int(fa), kAlpha - 2);
        const float tm = fm - i, ta = fa - j;
        const float e0 = e_[j][i] + (e_[j][i + 1] - e_[j][i]) * tm;
        const float e1 = e_[j + 1][i] + (e_[j + 1][i + 1] - e_[j + 1][i]) * tm;
        return e0 + (e1 - e0) * ta;
    }
    float average(float alpha) const { return lerp_alpha(avg_, alpha); }
    float profile_mean(float alpha) const { return lerp_alpha(profile_mean_, alpha); }

private:
    static float lerp_alpha(const float (&v)[kAlpha], float alpha) {
        const float fa = std::clamp(alpha, 0.0f, 1.0f) * (kAlpha - 1);
        const int j = std::min(int(fa), kAlpha - 2);
        return v[j] + (v[j + 1] - v[j]) * (fa - j);
    }
    float e_[kAlpha][kMu];
    float avg_[kAlpha];
    float profile_mean_[kAlpha];
};

const GgxAlbedoTable& ggx_albedo_table() {
    static const GgxAlbedoTable table;  // built once, on first use; thread-safe (C++11 function-local static)
    return table;
}

// The isotropic α the table is read at: the geometric mean for an anisotropic lobe (an approximation).
float table_alpha(Alphas a) { return std::sqrt(a.x * a.y); }

// The multiple-scattering part of a multi_ggx lobe (f, already × weight) and its cosine-sampling probability.
struct MultiScatter {
    glm::vec3 f{0.0f};
    float probability = 0.0f;  // of sampling the compensation lobe (cosine) instead of visible normals
};
MultiScatter multi_scatter(const Lobe& lobe, Alphas a, float mu_o, float mu_i, MultiScatterEstimate estimate) {
    const GgxAlbedoTable& table = ggx_albedo_table();
    const float alpha = table_alpha(a);
    const float e_o = table.albedo(mu_o, alpha);
    const float e_avg = table.average(alpha);
    MultiScatter out;
    out.probability = std::clamp(1.0f - e_o, 0.0f, 1.0f);
    if (!(1.0f - e_avg > 1e-6f) || mu_i <= 0.0f) return out;
    const float e_i = table.albedo(mu_i, alpha);
    const float base = (1.0f - e_o) * (1.0f - e_i) / (kPi * (1.0f - e_avg));
    glm::vec3 fms;
    if (lobe.fresnel == FresnelKind::none) {
        // Glossy BSDF: Cycles' random walk (mf_sample) multiplies the throughput by the colour at every bounce
        // after the first (specular_color here; the first bounce's is in the weight already), so light that
        // leaves after k extra bounces keeps tint^k. With a constant chance q of leaving at each extra bounce that
        // sums to T = tint q / (1 − tint (1 − q)); white (tint 1) keeps T = 1 whatever q. Kulla & Conty's
        // q = E_avg(α) is far too low (the walk leaves sooner): fitted to Cycles 3.4's own furnace albedos
        // (docs/closures.md), q = 1 − 0.43 α (s(μ_o) + s(μ_i) − s̄(α)), s(μ) = √μ, s̄ the mean of s over this
        // lobe's directions: symmetric in wi and wo, and its albedo for wo keeps q(μ_o) = 1 − 0.43 α s(μ_o) on
        // average (fresh light escapes sooner from grazing views; rough surfaces hold it longer).
        const float q = std::clamp(
            1.0f - kMultiTintSlope * alpha *
                       (multi_tint_profile(mu_o) + multi_tint_profile(mu_i) - table.profile_mean(alpha)),
            0.02f, 1.0f);
        glm::vec3 tint = glm::clamp(lobe.specular_color, 0.0f, 1.0f);
        // Cycles' evaluation towards a light sample (mf_eval) multiplies each extra bounce by the colour twice
        // (the walk's throughput enters both its phase and its sum): a tint² per bounce.
        if (estimate == MultiScatterEstimate::light_sample) tint *= tint;
        fms = tint * q / (glm::vec3(1.0f) - tint * (1.0f - q));
    } else {
        // Kulla & Conty's Fresnel factor: the energy kept through all the bounces with the average Fresnel F_avg.
        // The walk keeps F_1 ... F_(k+1) after k extra bounces: Σ F_avg^(k+1) E_avg (1 − E_avg)^(k−1).
        const glm::vec3 f_avg = fresnel_average(lobe.fresnel, lobe.specular_color, lobe.eta);
        // Towards a light sample, Cycles' mf_eval keeps the square of the first k of them instead, (F_1 ... F_k)²:
        // the same for k = 1 (most of the light), F_avg² per bounce after it.
        const glm::vec3 per_bounce = estimate == MultiScatterEstimate::light_sample ? f_avg * f_avg : f_avg;
        fms = f_avg * f_avg * e_avg / (glm::vec3(1.0f) - per_bounce * (1.0f - e_avg));
    }
    out.f = lobe.weight * fms * base;
    return out;
}

// ---- Lobes in the local frame ------------------------------------------------------------------------------------

LobeValue zero_value() { return LobeValue{}; }

// Cycles 3.x's Multiscatter GGX Glass on one side (glass_multiscatter.h): its first scattering as Cycles' mf_eval
// evaluates it (multi_ggx_glass_single), and a cosine lobe for the light of the later ones. η = lobe.eta is seen
// from wo's side. p_multiple: the chance of sampling that cosine lobe.
struct MultiGlass {
    float f_single = 0.0f, pdf_single = 0.0f;
    glm::vec3 multiple{0.0f};  // albedo of the cosine lobe
    float p_multiple = 0.0f;
};
MultiGlass multi_ggx_glass(const Lobe& lobe, Alphas a, const glm::vec3& wi, const glm::vec3& wo) {
    const bool reflect = lobe.kind == ClosureKind::reflection;
    const float eta = lobe.eta;
    const GlassMultiscatterAlbedo albedo = glass_multiscatter_albedo(eta, a.x, wo.z, lobe.specular_color);
    MultiGlass out;
    out.multiple = reflect ? albedo.multiple_reflect : albedo.multiple_transmit;
    const float single = reflect ? albedo.single_reflect : albedo.single_transmit;
    const float m = sampling_weight_of(out.multiple);
    out.p_multiple = m + single > 0.0f ? std::clamp(m / (m + single), 0.0f, 1.0f) : 0.0f;
    out.f_single = multi_ggx_glass_single(eta, a.x, wi, wo, &out.pdf_single);
    return out;
}

// The key of Cycles' own evaluation walk for one pair of directions: a light sample's value is a fixed function of
// them, as random as the directions are.
uint64_t direction_pair_key(const glm::vec3& wi, const glm::vec3& wo) {
    uint64_t key = 0x6d756c7469676c61ull;
    for (const float v : {wi.x, wi.y, wi.z, wo.x, wo.y, wo.z}) {
        uint32_t bits = 0;
        std::memcpy(&bits, &v, sizeof bits);
        key = (key ^ bits) * 0x100000001b3ull;
        key ^= key >> 29;
    }
    return key;
}

// Walks per light sample's value: Cycles runs one; two halve the variance of its later scatterings.
constexpr int kLightValueWalks = 2;

LobeValue eval_multi_ggx_glass(const Lobe& lobe, Alphas a, const glm::vec3& wi, const glm::vec3& wo,
                               MultiScatterEstimate estimate) {
    const bool reflect = lobe.kind == ClosureKind::reflection;
    if (reflect ? !(wi.z > 0.0f) : !(wi.z < 0.0f)) return zero_value();
    const MultiGlass g = multi_ggx_glass(lobe, a, wi, wo);
    LobeValue out;
    out.f = estimate == MultiScatterEstimate::light_sample
                ? lobe.weight * cycles3_multi_glass_light_value(lobe.eta, a.x, lobe.specular_color, wi, wo,
                                                                kLightValueWalks, direction_pair_key(wi, wo))
                : lobe.weight * (g.f_single + g.multiple * kInvPi);
    out.pdf = (1.0f - g.p_multiple) * g.pdf_single + g.p_multiple * std::fabs(wi.z) * kInvPi;
    return out;
}

LobeValue eval_reflection(const Lobe& lobe, Alphas a, const glm::vec3& wi, const glm::vec3& wo,
                          MultiScatterEstimate estimate) {
    if (!(wi.z > 0.0f) || !(wo.z > 0.0f)) return zero_value();
    const glm::vec3 sum = wi + wo;
    const float len2 = glm::dot(sum, sum);
    if (!(len2 > 1e-12f)) return zero_value();
    const glm::vec3 h = sum / std::sqrt(len2);
    const float cos_oh = glm::dot(wo, h);
    float d, g1o, g1i, pdf;
    switch (lobe.distribution) {
        case Distribution::beckmann:
            d = beckmann_d(h, a);
            g1o = beckmann_g1(wo, a);
            g1i = beckmann_g1(wi, a);
            pdf = d * h.z / (4.0f * cos_oh);
            break;
        case Distribution::gtr1: {
            // Cycles' clearcoat, sampled as Cycles samples it: GGX visible normals of α (sample_local), with the
            // density it reports, G1(wo) D_GTR1 / (4 wo.z), which is not that sampler's. A sampled direction then
            // weighs F G1(wi) as in Cycles, and light sampling is weighed against it by that density: the same
            // estimate as Cycles', whose highlight of a small light is brighter than GTR1's (1.4x on seed 9 of
            // the random scenes, where the reference and Photon Splat showed 0.71 of it).
            d = gtr1_d(h.z, a.x);
            const Alphas masking{kClearcoatMaskingAlpha, kClearcoatMaskingAlpha};
            g1o = ggx_g1(wo, masking);
            g1i = ggx_g1(wi, masking);
            pdf = g1o * d / (4.0f * wo.z);
            break;
        }
        default:  // ggx, multi_ggx's single scattering
            d = ggx_d(h, a);
            g1o = ggx_g1(wo, a);
            g1i = ggx_g1(wi, a);
            pdf = g1o * d / (4.0f * wo.z);
            break;
    }
    // multi_ggx scatters once with Cycles' height-correlated G2 = 1 / (1 + Λ(wo) + Λ(wi)) (mf_eval_glossy)
    const float g = lobe.distribution == Distribution::multi_ggx ? ggx_g2_correlated(wo, wi, a) : g1o * g1i;
    LobeValue out;
    const glm::vec3 fresnel = fresnel_color(lobe.fresnel, lobe.specular_color, lobe.eta, glm::dot(wi, h));
    out.f = lobe.weight * fresnel * (d * g / (4.0f * wi.z * wo.z));
    out.pdf = pdf;
    if (lobe.distribution == Distribution::multi_ggx) {
        const MultiScatter ms = multi_scatter(lobe, a, wo.z, wi.z, estimate);
        out.f += ms.f;
        out.pdf = (1.0f - ms.probability) * pdf + ms.probability * wi.z * kInvPi;
    }
    return out;
}

// The Walter et al. BTDF as Cycles' bsdf_microfacet_{ggx,beckmann}_eval_transmit computes it (its η² included),
// with η = lobe.eta = n_other / n_this.
LobeValue eval_refraction(const Lobe& lobe, Alphas a, const glm::vec3& wi, const glm::vec3& wo,
                          MultiScatterEstimate estimate) {
    const float eta = lobe.eta;
    if (!(wo.z > 0.0f) || !(wi.z < 0.0f) || !(eta > 0.0f) || !std::isfinite(eta) ||
        std::fabs(eta - 1.0f) < kSingularEta)
        return zero_value();
    const glm::vec3 ht = -(wo + eta * wi);
    const float ht2 = glm::dot(ht, ht);
    if (!(ht2 > 1e-12f)) return zero_value();
    // The microfacet normal that refracts wo into wi, oriented to the outside (into a less dense medium it is
    // +(wo + η wi)).
    const glm::vec3 h = (eta > 1.0f ? ht : -ht) / std::sqrt(ht2);
    const float cos_oh = glm::dot(wo, h), cos_ih = glm::dot(wi, h);
    const bool beckmann = lobe.distribution == Distribution::beckmann;
    const float g1o = beckmann ? beckmann_g1(wo, a) : ggx_g1(wo, a);
    const float g1i = beckmann ? beckmann_g1(wi, a) : ggx_g1(wi, a);
    LobeValue out;
    if (!(h.z > 0.0f) || !(cos_oh > 0.0f) || !(cos_ih < 0.0f)) {
        // No microfacet refracts wo into wi, so no sampler draws wi. But towards a light sample Cycles evaluates a
        // refraction without asking (3.4's bsdf_microfacet_{ggx,beckmann}_eval_transmit, 4.x's
        // bsdf_microfacet_eval): D of the line through ht, the magnitudes of the cosines with it, and the density
        // of visible normals there, which the light sample is weighed against. A rough GGX glass cube lit from
        // behind, one bounce (tests/blender/test_reference_light_paths.py): without such pairs the light seen
        // through it came out 0.03-0.13 of Cycles in its blocks.
        if (estimate == MultiScatterEstimate::walk || !(std::fabs(h.z) > 0.0f)) return zero_value();
        const glm::vec3 up = h.z > 0.0f ? h : -h;
        const float d = beckmann ? beckmann_d(up, a) : ggx_d(up, a);
        const float common = d * eta * eta * std::fabs(cos_oh * cos_ih) / (wo.z * ht2);
        out.f = lobe.weight * (g1o * g1i * common / -wi.z);
        out.pdf = g1o * common;
        return out;
    }
    const float d = beckmann ? beckmann_d(h, a) : ggx_d(h, a);
    const float jacobian = eta * eta * -cos_ih / ht2;  // dω_h / dω_i
    out.f = lobe.weight * (g1o * g1i * d * cos_oh * jacobian / (wo.z * -wi.z));
    // Visible normals (GGX) or D cos θ_h (Beckmann), times the Jacobian.
    const float pdf_h = beckmann ? d * h.z : ggx_g1(wo, a) * cos_oh * d / wo.z;
    out.pdf = pdf_h * jacobian;
    return out;
}

// Cycles' bsdf_ashikhmin_velvet_eval, without its cosine: f = D G / (4 cos_o cos_i).
float velvet_value(float sigma, const glm::vec3& wi, const glm::vec3& wo) {
    if (!(wi.z > 0.0f) || !(wo.z > 1e-5f)) return 0.0f;
    const glm::vec3 sum = wi + wo;
    const float len2 = glm::dot(sum, sum);
    if (!(len2 > 1e-12f)) return 0.0f;
    const glm::vec3 h = sum / std::sqrt(len2);
    const float cos_nh = h.z, cos_ho = std::fabs(glm::dot(wo, h));
    if (!(std::fabs(cos_nh) < 1.0f - 1e-5f && cos_ho > 1e-5f)) return 0.0f;
    const float ratio = std::max(cos_nh / cos_ho, 1e-5f);
    const float g = std::min(1.0f, 2.0f * ratio * std::min(wo.z, wi.z));
    const float sin2 = 1.0f - cos_nh * cos_nh;
    const float inv_sigma2 = 1.0f / (sigma * sigma);
    const float d = std::exp(-(cos_nh * cos_nh / sin2) * inv_sigma2) * inv_sigma2 * kInvPi / (sin2 * sin2);
    return 0.25f * d * g / (wo.z * wi.z);
}

float oren_nayar_value(float roughness, const glm::vec3& wi, const glm::vec3& wo) {
    // Cycles' bsdf_oren_nayar: A = 1 / (π + (3π − 4)/6 σ), B = σ A, f = A + B max(0, cos φ) sin θ_max tan θ_min
    // in the form t = (wi·wo − cos_i cos_o) / max(cos_i, cos_o) where positive.
    const float sigma = std::clamp(roughness, 0.0f, 1.0f);
    const float div = 1.0f / (kPi + ((3.0f * kPi - 4.0f) / 6.0f) * sigma);
    const float nl = std::max(wi.z, 0.0f), nv = std::max(wo.z, 0.0f);
    float t = glm::dot(wi, wo) - nl * nv;
    if (t > 0.0f) t /= std::max(nl, nv) + 1.17549435e-38f;
    return div + sigma * div * t;
}

float principled_diffuse_value(float roughness, const glm::vec3& wi, const glm::vec3& wo) {
    // Cycles' bsdf_principled_diffuse_compute_brdf, PRINCIPLED_DIFFUSE_FULL: Lambert with Schlick-shaped edges
    // plus Burley's retro-reflection, RR = roughness (1 + wi·wo) = 2 roughness (wi·h)².
    const float fv = schlick_weight(wo.z), fl = schlick_weight(wi.z);
    const float lambert = (1.0f - 0.5f * fv) * (1.0f - 0.5f * fl);
    const float rr = roughness * (glm::dot(wi, wo) + 1.0f);
    return kInvPi * (lambert + rr * (fl + fv + fl * fv * (rr - 1.0f)));
}

float sheen_value(const glm::vec3& wi, const glm::vec3& wo) {
    // Cycles' bsdf_principled_sheen: its eval returns (1 − wi·h)^5 cos θ_i, so f = (1 − wi·h)^5 (no 1/π).
    const glm::vec3 sum = wi + wo;
    const float len2 = glm::dot(sum, sum);
    if (!(len2 > 1e-12f)) return 0.0f;
    return schlick_weight(glm::dot(wi, sum) / std::sqrt(len2));
}

float velvet_sigma(float roughness) { return std::max(roughness, 0.01f); }  // Cycles' velvet setup

LobeValue eval_local(const Lobe& lobe, const glm::vec3& wi, const glm::vec3& wo,
                     MultiScatterEstimate estimate = MultiScatterEstimate::walk) {
    if (!(wo.z > 0.0f)) return zero_value();
    LobeValue out;
    switch (lobe.kind) {
        case ClosureKind::diffuse:
            if (!(wi.z > 0.0f)) return zero_value();
            out.f = lobe.weight * (lobe.roughness > 0.0f ? oren_nayar_value(lobe.roughness, wi, wo) : kInvPi);
            out.pdf = wi.z * kInvPi;
            return out;
        case ClosureKind::principled_diffuse:
            if (!(wi.z > 0.0f)) return zero_value();
            out.f = lobe.weight * principled_diffuse_value(lobe.roughness, wi, wo);
            out.pdf = wi.z * kInvPi;
            return out;
        case ClosureKind::translucent:
            if (!(wi.z < 0.0f)) return zero_value();
            out.f = lobe.weight * kInvPi;
            out.pdf = -wi.z * kInvPi;
            return out;
        case ClosureKind::sheen:
            if (!(wi.z > 0.0f)) return zero_value();
            out.f = lobe.weight * sheen_value(wi, wo);
            out.pdf = wi.z * kInvPi;
            return out;
        case ClosureKind::velvet:
            if (!(wi.z > 0.0f)) return zero_value();
            out.f = lobe.weight * velvet_value(velvet_sigma(lobe.roughness), wi, wo);
            out.pdf = 0.5f * kInvPi;
            return out;
        case ClosureKind::reflection: {
            Alphas a;
            if (lobe.distribution == Distribution::sharp || !lobe_alphas(lobe, a)) return zero_value();
            if (lobe.distribution == Distribution::multi_ggx_glass)
                return eval_multi_ggx_glass(lobe, a, wi, wo, estimate);
            return eval_reflection(lobe, a, wi, wo, estimate);
        }
        case ClosureKind::refraction: {
            Alphas a;
            if (lobe.distribution == Distribution::multi_ggx_glass)
                return lobe_alphas(lobe, a) ? eval_multi_ggx_glass(lobe, a, wi, wo, estimate) : zero_value();
            if (lobe.distribution == Distribution::sharp || lobe.distribution == Distribution::gtr1 ||
                !lobe_alphas(lobe, a))
                return zero_value();
            return eval_refraction(lobe, a, wi, wo, estimate);
        }
        case ClosureKind::transparent: return zero_value();
    }
    return zero_value();
}

// Draws a local wi; the value and density come from eval_local afterwards, so they agree by construction (the
// clearcoat's density is the one Cycles reports, not its sampler's: see eval_reflection).
// Returns false where the sample fails.
bool sample_local(const Lobe& lobe, const glm::vec3& wo, float u1, float u2, glm::vec3& wi) {
    switch (lobe.kind) {
        case ClosureKind::diffuse:
        case ClosureKind::principled_diffuse:
        case ClosureKind::sheen: wi = cosine_hemisphere_local(u1, u2); return true;
        case ClosureKind::translucent:
            wi = cosine_hemisphere_local(u1, u2);
            wi.z = -wi.z;
            return true;
        case ClosureKind::velvet: {  // uniform over the hemisphere, as Cycles
            const float z = 1.0f - u1, r = std::sqrt(std::max(0.0f, 1.0f - z * z)), phi = kTwoPi * u2;
            wi = glm::vec3(r * std::cos(phi), r * std::sin(phi), z);
            return z > 0.0f;
        }
        case ClosureKind::reflection: {
            Alphas a;
            if (lobe.distribution == Distribution::sharp || !lobe_alphas(lobe, a)) return false;
            glm::vec3 h;
            switch (lobe.distribution) {
                case Distribution::beckmann: h = sample_beckmann_normal(a, u1, u2); break;
                case Distribution::gtr1: h = sample_ggx_visible_normal(wo, a, u1, u2); break;  // as Cycles
                case Distribution::multi_ggx:
                case Distribution::multi_ggx_glass: {
                    // The light scattered more than once: a cosine lobe, drawn by its share of the light.
                    const float p_ms = lobe.distribution == Distribution::multi_ggx
                                           ? multi_scatter(lobe, a, wo.z, 0.0f, MultiScatterEstimate::walk).probability
                                           : multi_ggx_glass(lobe, a, wo, wo).p_multiple;
                    if (u1 < p_ms) {
                        wi = cosine_hemisphere_local(std::min(u1 / p_ms, 0.99999994f), u2);
                        return true;
                    }
                    u1 = std::min((u1 - p_ms) / (1.0f - p_ms), 0.99999994f);
                    h = sample_ggx_visible_normal(wo, a, u1, u2);
                    break;
                }
                default: h = sample_ggx_visible_normal(wo, a, u1, u2); break;
            }
            const float c = glm::dot(wo, h);
            if (!(c > 0.0f)) return false;
            wi = glm::normalize(2.0f * c * h - wo);
            return wi.z > 0.0f;
        }
        case ClosureKind::refraction: {
            Alphas a;
            const float eta = lobe.eta;
            if (lobe.distribution == Distribution::sharp || lobe.distribution == Distribution::gtr1 ||
                !lobe_alphas(lobe, a) || !(eta > 0.0f) || !std::isfinite(eta) ||
                std::fabs(eta - 1.0f) < kSingularEta)
                return false;
            if (lobe.distribution == Distribution::multi_ggx_glass) {
                const float p_ms = multi_ggx_glass(lobe, a, -wo, wo).p_multiple;
                if (u1 < p_ms) {
                    wi = cosine_hemisphere_local(std::min(u1 / p_ms, 0.99999994f), u2);
                    wi.z = -wi.z;
                    return wi.z < 0.0f;
                }
                u1 = std::min((u1 - p_ms) / (1.0f - p_ms), 0.99999994f);
            }
            const glm::vec3 h = lobe.distribution == Distribution::beckmann
                                    ? sample_beckmann_normal(a, u1, u2)
                                    : sample_ggx_visible_normal(wo, a, u1, u2);
            const float c = glm::dot(wo, h);
            if (!(c > 0.0f)) return false;
            // Snell through the microfacet, from wo's side (index 1) into the other (index η). Total internal
            // reflection fails the sample, as in Cycles (its refraction closure never reflects).
            const float sin2_t = (1.0f - c * c) / (eta * eta);
            if (sin2_t >= 1.0f) return false;
            const float cos_t = std::sqrt(1.0f - sin2_t);
            wi = glm::normalize(-wo / eta + (c / eta - cos_t) * h);
            return wi.z < 0.0f;
        }
        case ClosureKind::transparent: return false;
    }
    return false;
}

bool usable_directions(const glm::vec3& n, const glm::vec3& wo) { return finite3(n) && finite3(wo); }

LobeValue sanitized(LobeValue v) {
    if (!finite3(v.f) || !std::isfinite(v.pdf) || !(v.pdf >= 0.0f) || v.f.x < 0.0f || v.f.y < 0.0f ||
        v.f.z < 0.0f)
        return LobeValue{};
    return v;
}

template <typename E, size_t N>
E enum_from_string(const std::string& name, const std::array<E, N>& values, const char* field) {
    std::string names;
    for (size_t i = 0; i < N; ++i) {
        if (name == to_string(values[i])) return values[i];
        names += (i == 0 ? "'" : i + 1 == N ? " or '" : ", '") + std::string(to_string(values[i])) + "'";
    }
    throw InvalidInput(field, "must be " + names + ", got '" + name + "'");
}

std::string number(float v) { return std::to_string(v); }

}  // namespace

// ---- Names ---------------------------------------------------------------------------------------------------------

const char* to_string(ClosureKind kind) {
    switch (kind) {
        case ClosureKind::diffuse: return "diffuse";
        case ClosureKind::principled_diffuse: return "principled_diffuse";
        case ClosureKind::translucent: return "translucent";
        case ClosureKind::reflection: return "reflection";
        case ClosureKind::refraction: return "refraction";
        case ClosureKind::transparent: return "transparent";
        case ClosureKind::sheen: return "sheen";
        case ClosureKind::velvet: return "velvet";
    }
    return "?";
}
ClosureKind closure_kind_from_string(const std::string& name) {
    static constexpr std::array<ClosureKind, kClosureKindCount> all{
        ClosureKind::diffuse,    ClosureKind::principled_diffuse, ClosureKind::translucent, ClosureKind::reflection,
        ClosureKind::refraction, ClosureKind::transparent,        ClosureKind::sheen,       ClosureKind::velvet};
    return enum_from_string(name, all, "closure.kind");
}

const char* to_string(Distribution d) {
    switch (d) {
        case Distribution::sharp: return "sharp";
        case Distribution::ggx: return "ggx";
        case Distribution::beckmann: return "beckmann";
        case Distribution::multi_ggx: return "multi_ggx";
        case Distribution::gtr1: return "gtr1";
        case Distribution::multi_ggx_glass: return "multi_ggx_glass";
    }
    return "?";
}
Distribution distribution_from_string(const std::string& name) {
    static constexpr std::array<Distribution, 6> all{Distribution::sharp,     Distribution::ggx,
                                                     Distribution::beckmann,  Distribution::multi_ggx,
                                                     Distribution::gtr1,      Distribution::multi_ggx_glass};
    return enum_from_string(name, all, "closure.distribution");
}

const char* to_string(FresnelKind f) {
    switch (f) {
        case FresnelKind::none: return "none";
        case FresnelKind::principled: return "principled";
        case FresnelKind::dielectric: return "dielectric";
        case FresnelKind::schlick: return "schlick";
    }
    return "?";
}
FresnelKind fresnel_kind_from_string(const std::string& name) {
    static constexpr std::array<FresnelKind, 4> all{FresnelKind::none, FresnelKind::principled,
                                                    FresnelKind::dielectric, FresnelKind::schlick};
    return enum_from_string(name, all, "closure.fresnel");
}

const char* to_string(FactorKind f) {
    switch (f) {
        case FactorKind::fresnel: return "fresnel";
        case FactorKind::layer_fresnel: return "layer_fresnel";
        case FactorKind::layer_facing: return "layer_facing";
    }
    return "?";
}
FactorKind factor_kind_from_string(const std::string& name) {
    static constexpr std::array<FactorKind, 3> all{FactorKind::fresnel, FactorKind::layer_fresnel,
                                                   FactorKind::layer_facing};
    return enum_from_string(name, all, "factor.kind");
}

const char* to_string(TextureTarget t) {
    switch (t) {
        case TextureTarget::color: return "color";
        case TextureTarget::specular_color: return "specular_color";
    }
    return "?";
}
TextureTarget texture_target_from_string(const std::string& name) {
    static constexpr std::array<TextureTarget, 2> all{TextureTarget::color, TextureTarget::specular_color};
    return enum_from_string(name, all, "closure.texture_target");
}

// ---- Validation ------------------------------------------------------------------------------------------------

void validate(const Closure& c, int factor_count, const std::string& where) {
    if (static_cast<unsigned>(c.kind) >= static_cast<unsigned>(kClosureKindCount))
        throw InvalidInput(where + ".kind", "unknown closure kind " + std::to_string(int(c.kind)));
    if (static_cast<unsigned>(c.distribution) > static_cast<unsigned>(Distribution::multi_ggx_glass))
        throw InvalidInput(where + ".distribution", "unknown distribution " + std::to_string(int(c.distribution)));
    if (static_cast<unsigned>(c.fresnel) > static_cast<unsigned>(FresnelKind::schlick))
        throw InvalidInput(where + ".fresnel", "unknown Fresnel kind " + std::to_string(int(c.fresnel)));
    if (static_cast<unsigned>(c.texture_target) > static_cast<unsigned>(TextureTarget::specular_color))
        throw InvalidInput(where + ".texture_target", "unknown texture target");
    if (!is_finite(c.color) || c.color.x < 0.0f || c.color.y < 0.0f || c.color.z < 0.0f)
        throw InvalidInput(where + ".color", "each channel must be finite and >= 0");
    const glm::vec3& s = c.specular_color;
    if (!is_finite(s) || s.x < 0.0f || s.y < 0.0f || s.z < 0.0f || s.x > 1.0f || s.y > 1.0f || s.z > 1.0f)
        throw InvalidInput(where + ".specular_color", "each channel must be finite and in [0, 1]");
    if (!(c.roughness >= 0.0f && c.roughness <= 1.0f))
        throw InvalidInput(where + ".roughness", "must be finite and in [0, 1], got " + number(c.roughness));
    if (!(c.alpha_x >= 0.0f && c.alpha_x <= 1.0f))
        throw InvalidInput(where + ".alpha_x", "must be finite and in [0, 1], got " + number(c.alpha_x));
    if (!(c.alpha_y >= 0.0f && c.alpha_y <= 1.0f))
        throw InvalidInput(where + ".alpha_y", "must be finite and in [0, 1], got " + number(c.alpha_y));
    if (!(c.reported_alpha >= 0.0f && c.reported_alpha <= 1.0f))
        throw InvalidInput(where + ".reported_alpha", "must be finite and in [0, 1], got " + number(c.reported_alpha));
    if (c.reported_alpha > 0.0f && !(c.kind == ClosureKind::reflection && c.distribution == Distribution::sharp))
        throw InvalidInput(where + ".reported_alpha", "is for a sharp reflection only");
    if (!(std::isfinite(c.ior) && c.ior > 0.0f))
        throw InvalidInput(where + ".ior", "must be finite and > 0, got " + number(c.ior));
    if (c.texture < -1)
        throw InvalidInput(where + ".texture", "must be -1 (none) or a texture index, got " + std::to_string(c.texture));
    if (c.kind == ClosureKind::refraction && c.distribution == Distribution::gtr1)
        throw InvalidInput(where + ".distribution", "'gtr1' (clearcoat) is a reflection distribution only");
    if (c.distribution == Distribution::multi_ggx_glass &&
        !(c.kind == ClosureKind::reflection || c.kind == ClosureKind::refraction))
        throw InvalidInput(where + ".distribution", "'multi_ggx_glass' is for reflection and refraction only");
    const int count = std::clamp(factor_count, 0, 32);
    const uint32_t allowed = count >= 32 ? 0xFFFFFFFFu : ((1u << count) - 1u);
    if ((c.factors_on & ~allowed) != 0)
        throw InvalidInput(where + ".factors_on",
                           "names a factor the material does not have (it has " + std::to_string(factor_count) + ")");
    if ((c.factors_off & ~allowed) != 0)
        throw InvalidInput(where + ".factors_off",
                           "names a factor the material does not have (it has " + std::to_string(factor_count) + ")");
    if ((c.factors_on & c.factors_off) != 0)
        throw InvalidInput(where + ".factors_off", "a factor cannot be both on and off (factors_on & factors_off)");
}

void validate(const MixFactor& f, const std::string& where) {
    if (static_cast<unsigned>(f.kind) > static_cast<unsigned>(FactorKind::layer_facing))
        throw InvalidInput(where + ".kind", "unknown factor kind " + std::to_string(int(f.kind)));
    if (!std::isfinite(f.value)) throw InvalidInput(where + ".value", "must be finite");
    if (f.kind == FactorKind::fresnel && !(f.value > 0.0f))
        throw InvalidInput(where + ".value", "the Fresnel IOR must be > 0, got " + number(f.value));
    if (f.kind != FactorKind::fresnel && !(f.value >= 0.0f && f.value <= 1.0f))
        throw InvalidInput(where + ".value", "the Layer Weight blend must be in [0, 1], got " + number(f.value));
}

// ---- Factors and Fresnel -----------------------------------------------------------------------------------------

float fresnel_dielectric_cos(float cos_i, float eta) {
    const float c = std::fabs(cos_i);
    float g = eta * eta - 1.0f + c * c;
    if (!(g > 0.0f)) return 1.0f;  // total internal reflection (or a meaningless η)
    g = std::sqrt(g);
    const float a = (g - c) / (g + c);
    const float b = (c * (g + c) - 1.0f) / (c * (g - c) + 1.0f);
    const float f = 0.5f * a * a * (1.0f + b * b);
    return std::isfinite(f) ? std::min(f, 1.0f) : 1.0f;
}

float evaluate_factor(const MixFactor& f, float cos_no, bool backfacing) {
    float value = 0.0f;
    switch (f.kind) {
        case FactorKind::fresnel: {  // Cycles' svm_node_fresnel
            float eta = std::max(f.value, 1e-5f);
            if (backfacing) eta = 1.0f / eta;
            value = fresnel_dielectric_cos(cos_no, eta);
            break;
        }
        case FactorKind::layer_fresnel: {  // svm_node_layer_weight, Fresnel output: η = 1 / (1 − blend) in front
            float eta = std::max(1.0f - f.value, 1e-5f);
            if (!backfacing) eta = 1.0f / eta;
            value = fresnel_dielectric_cos(cos_no, eta);
            break;
        }
        case FactorKind::layer_facing: {  // svm_node_layer_weight, Facing output: 1 − |cos|^e
            float c = std::fabs(cos_no);
            if (f.value != 0.5f) {
                const float blend = std::clamp(f.value, 0.0f, 1.0f - 1e-5f);
                c = std::pow(c, blend < 0.5f ? 2.0f * blend : 0.5f / (1.0f - blend));
            }
            value = 1.0f - c;
            break;
        }
    }
    if (!std::isfinite(value)) return 0.0f;
    return std::clamp(value, 0.0f, 1.0f);
}

glm::vec3 sharp_reflection_fresnel(FresnelKind fresnel, const glm::vec3& specular_color, float ior, float cos_no) {
    const glm::vec3 f = fresnel_color(fresnel, specular_color, ior, std::clamp(cos_no, 0.0f, 1.0f));
    return finite3(f) ? glm::clamp(f, 0.0f, 1.0f) : glm::vec3(0.0f);
}

// ---- Lobes -------------------------------------------------------------------------------------------------------

LobeValue lobe_eval(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wi, const glm::vec3& wo,
                    MultiScatterEstimate estimate) {
    if (!usable_directions(n, wo) || !finite3(wi)) return LobeValue{};
    Frame frame;
    if (!lobe_frame(lobe, n, frame)) return LobeValue{};
    return sanitized(eval_local(lobe, frame.to_local(wi), frame.to_local(wo), estimate));
}

float lobe_sampler_pdf(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wi, const glm::vec3& wo) {
    if (lobe.kind != ClosureKind::reflection || lobe.distribution != Distribution::gtr1)
        return lobe_eval(lobe, n, wi, wo).pdf;
    Frame frame;
    Alphas a;
    if (!usable_directions(n, wo) || !finite3(wi) || !lobe_frame(lobe, n, frame) || !lobe_alphas(lobe, a)) return 0.0f;
    const glm::vec3 i = frame.to_local(wi), o = frame.to_local(wo);
    if (!(i.z > 0.0f) || !(o.z > 0.0f)) return 0.0f;
    const glm::vec3 sum = i + o;
    const float len2 = glm::dot(sum, sum);
    if (!(len2 > 1e-12f)) return 0.0f;
    // GGX's visible-normal density of h, carried to wi by the mirror's Jacobian: G1(wo) D(h) / (4 wo.z).
    const float pdf = ggx_g1(o, a) * ggx_d(sum / std::sqrt(len2), a) / (4.0f * o.z);
    return std::isfinite(pdf) && pdf > 0.0f ? pdf : 0.0f;
}

float lobe_reported_pdf(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wi, const glm::vec3& wo) {
    if (lobe.distribution != Distribution::multi_ggx_glass)
        return lobe_eval(lobe, n, wi, wo,
                         lobe.kind == ClosureKind::refraction ? MultiScatterEstimate::light_sample
                                                              : MultiScatterEstimate::walk)
            .pdf;
    Frame frame;
    Alphas a;
    if (!usable_directions(n, wo) || !finite3(wi) || !lobe_frame(lobe, n, frame) || !lobe_alphas(lobe, a)) return 0.0f;
    const glm::vec3 i = frame.to_local(wi), o = frame.to_local(wo);
    const bool reflect = lobe.kind == ClosureKind::reflection;
    if (!(o.z > 0.0f) || (reflect ? !(i.z > 0.0f) : !(i.z < 0.0f))) return 0.0f;
    return cycles3_multi_glass_pdf(lobe.eta, a.x, i, o);
}

LobeSample lobe_sample(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wo, float u1, float u2) {
    LobeSample out;
    out.direction = n;
    if (!usable_directions(n, wo)) return out;
    Frame frame;
    if (!lobe_frame(lobe, n, frame)) return out;
    const glm::vec3 wo_local = frame.to_local(wo);
    if (!(wo_local.z > 0.0f)) return out;
    u1 = std::clamp(u1, 0.0f, 0.99999994f);
    u2 = std::clamp(u2, 0.0f, 0.99999994f);
    glm::vec3 wi_local;
    if (!sample_local(lobe, wo_local, u1, u2, wi_local) || !finite3(wi_local)) return out;
    const LobeValue v = sanitized(eval_local(lobe, wi_local, wo_local));
    if (!(v.pdf > 0.0f)) return out;
    out.direction = glm::normalize(frame.to_world(wi_local));
    out.f = v.f;
    out.pdf = v.pdf;
    return out;
}

namespace {
// Smith Λ of a direction at cos θ from the normal, as Cycles' mf_lambda (0 within 1e-4 of the normal).
float cycles3_lambda(float a2, float cos_t) {
    if (cos_t > 0.9999f) return 0.0f;
    const float tan2 = (1.0f - cos_t * cos_t) / std::max(cos_t * cos_t, 1e-7f);
    return 0.5f * (std::sqrt(1.0f + a2 * tan2) - 1.0f);
}
}  // namespace

Cycles3MirrorValue cycles3_multiscatter_mirror_eval(float alpha, const glm::vec3& n, const glm::vec3& wi,
                                                    const glm::vec3& wo) {
    Cycles3MirrorValue out;
    const float cos_o = glm::dot(n, wo), cos_i = glm::dot(n, wi);
    if (!(alpha > 0.0f) || !(cos_o > 0.0f) || !(cos_i > 0.0f)) return out;
    alpha = std::min(alpha, 1.0f);
    const float a2 = alpha * alpha;
    const glm::vec3 sum = wi + wo;
    const float len2 = glm::dot(sum, sum);
    if (!(len2 > 0.0f)) return out;
    const float cos_h = std::min(glm::dot(n, sum) / std::sqrt(len2), 1.0f);
    // D as Cycles' multiscatter D_ggx clamps it: α² / max(π tmp², 1e-7), tmp = sin²θ_h + α² cos²θ_h.
    const float tmp = (1.0f - cos_h * cos_h) + a2 * cos_h * cos_h;
    const float d = a2 / std::max(kPi * tmp * tmp, 1e-7f);
    const float lambda_o = cycles3_lambda(a2, std::min(cos_o, 1.0f)), lambda_i = cycles3_lambda(a2, std::min(cos_i, 1.0f));
    out.f = d / (4.0f * cos_o * cos_i * (1.0f + lambda_o + lambda_i));  // mf_eval's single scattering, G2
    // mf_ggx_pdf: its single scattering's density, and a cosine lobe for the rest, split by mf_ggx_albedo, Cycles'
    // fit of the single-scattering albedo of r = α.
    const float r = alpha;
    float albedo = 0.806495f * std::exp(-1.98712f * r * r) + 0.199531f;
    albedo -= ((((((1.76741f * r - 8.43891f) * r + 15.784f) * r - 14.398f) * r + 6.45221f) * r - 1.19722f) * r +
               0.027803f) * r + 0.00568739f;
    albedo = std::clamp(albedo, 0.0f, 1.0f);
    const float single = 0.25f * d / std::max((1.0f + lambda_o) * cos_o, 1e-7f);
    out.pdf = albedo * single + (1.0f - albedo) * cos_i * kInvPi;
    return out;
}

float cycles3_multiscatter_mirror_pdf(float alpha, float cos_o) {
    if (!(cos_o > 0.0f)) return 0.0f;
    cos_o = std::min(cos_o, 1.0f);
    const glm::vec3 n(0.0f, 0.0f, 1.0f), wo(std::sqrt(1.0f - cos_o * cos_o), 0.0f, cos_o);
    return cycles3_multiscatter_mirror_eval(alpha, n, glm::vec3(-wo.x, 0.0f, wo.z), wo).pdf;
}

float lobe_sampling_weight(const Lobe& lobe, const glm::vec3& n, const glm::vec3& wo) {
    const float cos_o = glm::dot(n, wo);
    if (!(cos_o > 0.0f) || !finite3(lobe.weight)) return 0.0f;
    float w = sampling_weight_of(lobe.weight);
    switch (lobe.kind) {
        case ClosureKind::reflection:
            // Cycles' Fresnel closures multiply theirs by the mean of their Fresnel colour at wo.
            w *= sampling_weight_of(fresnel_color(lobe.fresnel, lobe.specular_color, lobe.eta, cos_o));
            break;
        case ClosureKind::sheen:
            // The sheen's albedo is about 0.08 (1 − cos θ_o)² (measured: 0.0056 at cos 0.7, 0.034 at 0.3, 0.083 at
            // 0.02; docs/closures.md), tiny at normal incidence.
            w *= 0.08f * (1.0f - cos_o) * (1.0f - cos_o) + 0.001f;
            break;
        default: break;
    }
    if (lobe.distribution == Distribution::multi_ggx_glass) {
        // The walk's light on this side (its Fresnel split among it), not a Fresnel colour of the weight.
        const GlassMultiscatterAlbedo albedo =
            glass_multiscatter_albedo(lobe.eta, lobe.alpha_x, cos_o, lobe.specular_color);
        const bool reflect = lobe.kind == ClosureKind::reflection;
        w = sampling_weight_of(lobe.weight) *
            ((reflect ? albedo.single_reflect : albedo.single_transmit) +
             sampling_weight_of(reflect ? albedo.multiple_reflect : albedo.multiple_transmit));
    }
    return std::isfinite(w) ? std::max(w, 0.0f) : 0.0f;
}

glm::vec3 ensure_valid_reflection(const glm::vec3& ng, const glm::vec3& i, const glm::vec3& n) {
    const glm::vec3 r = 2.0f * glm::dot(n, i) * n - i;
    // A reflection may be as shallow as the incoming ray, never shallower than that (or than 0.01).
    const float threshold = std::min(0.9f * glm::dot(ng, i), 0.01f);
    if (glm::dot(ng, r) >= threshold) return n;
    // In the frame (x, ng) with n in its plane, the tilted n' = (sqrt(1 − z²), z) solves
    // 2 (n'·i) n'_z − i_z = threshold: a quadratic in z², of two roots.
    const float n_dot_ng = glm::dot(n, ng);
    const glm::vec3 along = n - n_dot_ng * ng;
    const float along_len = glm::length(along);
    if (!(along_len > 0.0f)) return ng;
    const glm::vec3 x = along / along_len;
    const float ix = glm::dot(i, x), iz = glm::dot(i, ng);
    const float ix2 = ix * ix, iz2 = iz * iz;
    const float a = ix2 + iz2;
    if (!(a > 0.0f)) return ng;
    const float b = std::sqrt(std::max(ix2 * (a - threshold * threshold), 0.0f));
    const float c = iz * threshold + a;
    const float z2_1 = 0.5f / a * (b + c), z2_2 = 0.5f / a * (-b + c);
    bool valid1 = z2_1 > 1e-5f && z2_1 <= 1.0f + 1e-5f;
    bool valid2 = z2_2 > 1e-5f && z2_2 <= 1.0f + 1e-5f;
    const auto planar = [](float z2) {
        return glm::vec2(std::sqrt(std::max(1.0f - z2, 0.0f)), std::sqrt(std::max(z2, 0.0f)));
    };
    glm::vec2 chosen;
    if (valid1 && valid2) {
        const glm::vec2 n1 = planar(z2_1), n2 = planar(z2_2);
        const float r1 = 2.0f * (n1.x * ix + n1.y * iz) * n1.y - iz;
        const float r2 = 2.0f * (n2.x * ix + n2.y * iz) * n2.y - iz;
        valid1 = r1 >= 1e-5f;
        valid2 = r2 >= 1e-5f;
        if (valid1 && valid2)
            chosen = r1 < r2 ? n1 : n2;  // the shallower reflection is the nearer to n
        else
            chosen = r1 > r2 ? n1 : n2;
    } else if (valid1 || valid2) {
        chosen = planar(valid1 ? z2_1 : z2_2);
    } else {
        return ng;
    }
    return chosen.x * x + chosen.y * ng;
}

}  // namespace ps
