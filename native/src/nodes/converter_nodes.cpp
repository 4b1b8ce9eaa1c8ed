// The converter nodes (shader_program.h's "converters" group): Math, Vector Math, Map Range, Clamp, Color Ramp,
// the curves, Mix, the colour adjustments, Separate/Combine Color, RGB to BW, Blackbody, Wavelength, Mapping and
// Vector Rotate, each giving what Blender 3.4's Cycles gives at a hit (its SVM kernel, plus what its Blender sync
// adds around a node: the Math node's clamp and the float Map Range's clamp are a Clamp node after it there).
// tests/native/test_converter_nodes.cpp checks every operation and mode against values Cycles rendered.
//
// Table layouts (offsets are params, in floats, into the program's `tables`):
//   color_ramp    params (offset, entries, interpolate): entries × (r, g, b, a), the ramp evaluated at
//                 i / (entries − 1) (Cycles bakes 256). Looked up at fac clamped to [0, 1], never extrapolated;
//                 interpolate 0 takes the entry below (Cycles' constant ramp), 1 blends the two around fac.
//   rgb_curves    params (offset, entries): min x, max x, then entries × (r, g, b): each channel's curve composed
//   vector_curves with the combined curve (rgb) or each axis' curve (vector), evaluated at
//                 min x + i / (entries − 1) × (max x − min x). A component is looked up at
//                 (value − min x) / (max x − min x); beyond [0, 1] the table is extended along the slope of its
//                 last (first) two entries, which is Cycles' "extrapolated" curve extension.
//   float_curve   params (offset, entries): min x, max x, then entries values; the same lookup.
// A ramp needs at least 1 entry and a curve 2; fewer, a negative offset or a null table gives zeros. That the
// table holds offset + the layout's size is validate()'s check (shader_program.h), not repeated per hit.
//
// Invalid modes (a param outside its enum) give zeros. Nothing here indexes memory from a float without
// clamping the index first, so NaN and infinite inputs give NaN or infinite outputs at worst, never a crash.
#include <cfloat>
#include <climits>
#include <cmath>

#include <glm/geometric.hpp>

#include "color_math.h"
#include "../shader/op_args.h"

namespace ps {

namespace {

constexpr float kPiF = 3.14159265358979323846f;

// --- Cycles' scalar building blocks ------------------------------------------------------------------------------

// C's float → int conversion as x86 performs it (cvttss2si): truncation, with NaN and out-of-range values giving
// INT_MIN. Cycles relies on the hardware here (safe_powf's integer test, the wavelength table index); doing it
// explicitly gives its results without the undefined behaviour.
int float_to_int(float f) {
    if (!(f >= -2147483648.0f && f < 2147483648.0f)) return INT_MIN;
    return static_cast<int>(f);
}

float safe_divide(float a, float b) { return b != 0.0f ? a / b : 0.0f; }
glm::vec3 safe_divide(const glm::vec3& a, const glm::vec3& b) {
    return {safe_divide(a.x, b.x), safe_divide(a.y, b.y), safe_divide(a.z, b.z)};
}
float safe_modulo(float a, float b) { return b != 0.0f ? std::fmod(a, b) : 0.0f; }

// A negative base only has a real power for an integer exponent; Cycles gives 0 otherwise.
float safe_pow(float a, float b) {
    if (a < 0.0f && b != static_cast<float>(float_to_int(b))) return 0.0f;
    return std::pow(a, b);
}

float safe_log(float a, float base) {
    if (a <= 0.0f || base <= 0.0f) return 0.0f;
    return safe_divide(std::log(a), std::log(base));
}

// Wrap into [min, max): the range's multiples are taken off; an empty range gives min.
float wrap(float value, float max, float min) {
    const float range = max - min;
    return range != 0.0f ? value - range * std::floor((value - min) / range) : min;
}

float pingpong(float a, float b) {
    if (b == 0.0f) return 0.0f;
    const float x = (a - b) / (b * 2.0f);
    return std::fabs((x - std::floor(x)) * b * 2.0f - b);
}

// The polynomial smooth minimum (Inigo Quilez's cubic): k is the distance over which the two blend.
float smooth_min(float a, float b, float k) {
    if (k == 0.0f) return std::fmin(a, b);
    const float h = std::fmax(k - std::fabs(a - b), 0.0f) / k;
    return std::fmin(a, b) - h * h * h * k * (1.0f / 6.0f);
}

float compatible_sign(float f) { return f == 0.0f ? 0.0f : (f < 0.0f ? -1.0f : 1.0f); }

float smoothstep(float edge0, float edge1, float x) {
    if (x < edge0) return 0.0f;
    if (x >= edge1) return 1.0f;
    const float t = (x - edge0) / (edge1 - edge0);
    return (3.0f - 2.0f * t) * (t * t);
}

float smootherstep(float edge0, float edge1, float x) {
    x = cclamp(safe_divide(x - edge0, edge1 - edge0), 0.0f, 1.0f);
    return x * x * x * (x * (x * 6.0f - 15.0f) + 10.0f);
}

glm::vec3 vfloor(const glm::vec3& a) { return {std::floor(a.x), std::floor(a.y), std::floor(a.z)}; }
glm::vec3 interp(const glm::vec3& a, const glm::vec3& b, float t) { return a + t * (b - a); }

// --- Math --------------------------------------------------------------------------------------------------------

// NodeMathType order.
bool math(int type, float a, float b, float c, float& r) {
    switch (type) {
        case 0: r = a + b; break;
        case 1: r = a - b; break;
        case 2: r = a * b; break;
        case 3: r = safe_divide(a, b); break;
        case 4: r = std::sin(a); break;
        case 5: r = std::cos(a); break;
        case 6: r = std::tan(a); break;
        case 7: r = std::asin(cclamp(a, -1.0f, 1.0f)); break;
        case 8: r = std::acos(cclamp(a, -1.0f, 1.0f)); break;
        case 9: r = std::atan(a); break;
        case 10: r = safe_pow(a, b); break;
        case 11: r = safe_log(a, b); break;
        case 12: r = std::fmin(a, b); break;
        case 13: r = std::fmax(a, b); break;
        case 14: r = std::floor(a + 0.5f); break;
        case 15: r = a < b ? 1.0f : 0.0f; break;
        case 16: r = a > b ? 1.0f : 0.0f; break;
        case 17: r = safe_modulo(a, b); break;
        case 18: r = std::fabs(a); break;
        case 19: r = std::atan2(a, b); break;
        case 20: r = std::floor(a); break;
        case 21: r = std::ceil(a); break;
        case 22: r = a - std::floor(a); break;
        case 23: r = std::sqrt(cmax(a, 0.0f)); break;
        case 24: r = a > 0.0f ? 1.0f / std::sqrt(a) : 0.0f; break;
        case 25: r = compatible_sign(a); break;
        case 26: r = std::exp(a); break;
        case 27: r = a * (kPiF / 180.0f); break;
        case 28: r = a * (180.0f / kPiF); break;
        case 29: r = std::sinh(a); break;
        case 30: r = std::cosh(a); break;
        case 31: r = std::tanh(a); break;
        case 32: r = a >= 0.0f ? std::floor(a) : std::ceil(a); break;
        case 33: r = std::floor(safe_divide(a, b)) * b; break;
        case 34: r = wrap(a, b, c); break;
        case 35: r = (a == b || std::fabs(a - b) <= std::fmax(c, FLT_EPSILON)) ? 1.0f : 0.0f; break;
        case 36: r = a * b + c; break;
        case 37: r = pingpong(a, b); break;
        case 38: r = smooth_min(a, b, c); break;
        case 39: r = -smooth_min(-a, -b, c); break;
        default: return false;
    }
    return true;
}

// --- Vector Math -------------------------------------------------------------------------------------------------

// Cycles' normalize divides by the length unguarded (Reflect and Refract use it: a zero normal gives NaN there
// too); safe_normalize leaves a zero vector as it is.
glm::vec3 normalize_unsafe(const glm::vec3& a) { return a / glm::length(a); }
glm::vec3 safe_normalize(const glm::vec3& a) {
    const float t = glm::length(a);
    return t != 0.0f ? a * (1.0f / t) : a;
}

glm::vec3 refract(const glm::vec3& incident, const glm::vec3& normal, float eta) {
    const float d = glm::dot(normal, incident);
    const float k = 1.0f - eta * eta * (1.0f - d * d);
    if (k < 0.0f) return glm::vec3(0.0f);  // total internal reflection
    return eta * incident - (eta * d + std::sqrt(k)) * normal;
}

// NodeVectorMathType order; `value` or `vector` is the op's result, the other stays 0.
bool vector_math(int type, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, float scale, float& value,
                 glm::vec3& vector) {
    value = 0.0f;
    vector = glm::vec3(0.0f);
    switch (type) {
        case 0: vector = a + b; break;
        case 1: vector = a - b; break;
        case 2: vector = a * b; break;
        case 3: vector = safe_divide(a, b); break;
        case 4: vector = glm::cross(a, b); break;
        case 5: {
            const float len2 = glm::dot(b, b);
            vector = len2 != 0.0f ? (glm::dot(a, b) / len2) * b : glm::vec3(0.0f);
            break;
        }
        case 6: {
            const glm::vec3 n = normalize_unsafe(b);
            vector = a - 2.0f * n * glm::dot(a, n);
            break;
        }
        case 7: value = glm::dot(a, b); break;
        case 8: value = glm::length(a - b); break;
        case 9: value = glm::length(a); break;
        case 10: vector = a * scale; break;
        case 11: vector = safe_normalize(a); break;
        case 12: vector = vfloor(safe_divide(a, b)) * b; break;
        case 13: vector = vfloor(a); break;
        case 14: vector = {std::ceil(a.x), std::ceil(a.y), std::ceil(a.z)}; break;
        case 15: vector = {safe_modulo(a.x, b.x), safe_modulo(a.y, b.y), safe_modulo(a.z, b.z)}; break;
        case 16: vector = a - vfloor(a); break;
        case 17: vector = glm::abs(a); break;
        case 18: vector = cmin(a, b); break;
        case 19: vector = cmax(a, b); break;
        case 20: vector = {wrap(a.x, b.x, c.x), wrap(a.y, b.y, c.y), wrap(a.z, b.z, c.z)}; break;
        case 21: vector = {std::sin(a.x), std::sin(a.y), std::sin(a.z)}; break;
        case 22: vector = {std::cos(a.x), std::cos(a.y), std::cos(a.z)}; break;
        case 23: vector = {std::tan(a.x), std::tan(a.y), std::tan(a.z)}; break;
        case 24: vector = refract(a, normalize_unsafe(b), scale); break;
        case 25: vector = glm::dot(c, b) < 0.0f ? a : -a; break;  // faceforward(a, incident b, reference c)
        case 26: vector = a * b + c; break;
        default: return false;
    }
    return true;
}

// --- Map Range and Clamp -----------------------------------------------------------------------------------------

// Clamp node: `range` orders min and max first, so a reversed range still clamps (Min Max does not: it returns max).
float clamp_node(float value, float lo, float hi, bool range) {
    return (range && lo > hi) ? cclamp(value, hi, lo) : cclamp(value, lo, hi);
}

bool map_range(int type, bool clamp, float value, float from_min, float from_max, float to_min, float to_max,
               float steps, float& r) {
    if (type < 0 || type > 3) return false;
    if (from_max != from_min) {
        float factor = value;
        switch (type) {
            case 0: factor = (value - from_min) / (from_max - from_min); break;
            case 1:
                factor = (value - from_min) / (from_max - from_min);
                factor = steps > 0.0f ? std::floor(factor * (steps + 1.0f)) / steps : 0.0f;
                break;
            case 2:
                factor = from_min > from_max ? 1.0f - smoothstep(from_max, from_min, factor)
                                             : smoothstep(from_min, from_max, factor);
                break;
            default:
                factor = from_min > from_max ? 1.0f - smootherstep(from_max, from_min, factor)
                                             : smootherstep(from_min, from_max, factor);
                break;
        }
        r = to_min + factor * (to_max - to_min);
    } else {
        r = 0.0f;  // an empty source range maps nothing
    }
    // Cycles' sync puts a Clamp node (range type, to min .. to max) after a clamped Map Range; the smooth modes
    // stay inside the target range anyway.
    if (clamp) r = clamp_node(r, to_min, to_max, true);
    return true;
}

// The vector Map Range is its own kernel in Cycles, with differences from the float one kept here: the factor is a
// safe division (an empty range gives factor 0, so to min, not 0), the smooth modes normalise before smoothing,
// and the clamp applies only to the linear and stepped modes.
bool map_range_vector(int type, bool clamp, const glm::vec3& value, const glm::vec3& from_min,
                      const glm::vec3& from_max, const glm::vec3& to_min, const glm::vec3& to_max,
                      const glm::vec3& steps, glm::vec3& r) {
    if (type < 0 || type > 3) return false;
    glm::vec3 factor = safe_divide(value - from_min, from_max - from_min);
    switch (type) {
        case 0: break;
        case 1:
            for (int k = 0; k < 3; ++k)
                factor[k] = steps[k] > 0.0f ? std::floor(factor[k] * (steps[k] + 1.0f)) / steps[k] : 0.0f;
            break;
        case 2:
            factor = cmin(cmax(factor, glm::vec3(0.0f)), glm::vec3(1.0f));
            factor = (glm::vec3(3.0f) - 2.0f * factor) * (factor * factor);
            break;
        default:
            factor = cmin(cmax(factor, glm::vec3(0.0f)), glm::vec3(1.0f));
            factor = factor * factor * factor * (factor * (factor * 6.0f - 15.0f) + 10.0f);
            break;
    }
    r = to_min + factor * (to_max - to_min);
    if (clamp && type <= 1)
        for (int k = 0; k < 3; ++k) r[k] = clamp_node(r[k], to_min[k], to_max[k], true);
    return true;
}

// --- Ramps and curves --------------------------------------------------------------------------------------------

// One channel of a baked table of `n` entries spaced `stride` floats apart, at f in table units [0, 1]. With
// `extrapolate`, beyond [0, 1] the table continues along its end segment's slope; otherwise f is clamped (NaN
// reads entry 0, as Cycles' clamp gives it).
float table_lookup(const float* t, int n, int stride, float f, bool interpolate, bool extrapolate) {
    if (extrapolate && (f < 0.0f || f > 1.0f)) {
        float t0, dy;
        if (f < 0.0f) {
            t0 = t[0];
            dy = t0 - t[stride];
            f = -f;
        } else {
            t0 = t[(n - 1) * stride];
            dy = t0 - t[(n - 2) * stride];
            f = f - 1.0f;
        }
        return t0 + dy * f * static_cast<float>(n - 1);
    }
    f = csaturate(f) * static_cast<float>(n - 1);
    int i = float_to_int(f);
    i = i < 0 ? 0 : (i > n - 1 ? n - 1 : i);
    const float frac = f - static_cast<float>(i);
    float a = t[i * stride];
    // frac > 0 only below the last entry, so i + 1 stays in the table
    if (interpolate && frac > 0.0f) a = (1.0f - frac) * a + frac * t[(i + 1) * stride];
    return a;
}

// Curves always extrapolate: that is Blender's default curve extension ("extrapolated"). Its other one,
// "extended horizontally", Cycles gives by looking up without extrapolation (the position clamped to the table);
// the op's params have no flag for it yet, so such a curve is right inside its range only. A third param (Cycles'
// `extrapolate`) passed here instead of this constant is all it would take.
constexpr bool kCurvesExtrapolate = true;

// --- Mix ---------------------------------------------------------------------------------------------------------

float overlay(float a, float b, float t) {
    const float tm = 1.0f - t;
    return a < 0.5f ? a * (tm + 2.0f * t * b) : 1.0f - (tm + 2.0f * t * (1.0f - b)) * (1.0f - a);
}

float dodge(float a, float b, float t) {
    if (a == 0.0f) return a;
    float tmp = 1.0f - t * b;
    if (tmp <= 0.0f) return 1.0f;
    tmp = a / tmp;
    return tmp > 1.0f ? 1.0f : tmp;
}

float burn(float a, float b, float t) {
    float tmp = (1.0f - t) + t * b;
    if (tmp <= 0.0f) return 0.0f;
    tmp = 1.0f - (1.0f - a) / tmp;
    if (tmp < 0.0f) return 0.0f;
    return tmp > 1.0f ? 1.0f : tmp;
}

// Cycles' NodeMix order: blend, add, multiply, subtract, screen, divide, difference, darken, lighten, overlay,
// dodge, burn, hue, saturation, value, color, soft light, linear light, and 18, the clamp Cycles' MixRGB appends.
bool mix_blend(int type, float t, const glm::vec3& a, const glm::vec3& b, glm::vec3& r) {
    const float tm = 1.0f - t;
    const glm::vec3 one(1.0f);
    switch (type) {
        case 0: r = interp(a, b, t); break;
        case 1: r = interp(a, a + b, t); break;
        case 2: r = interp(a, a * b, t); break;
        case 3: r = interp(a, a - b, t); break;
        case 4: r = one - (glm::vec3(tm) + t * (one - b)) * (one - a); break;
        case 5:
            r = a;
            for (int k = 0; k < 3; ++k)
                if (b[k] != 0.0f) r[k] = tm * a[k] + t * a[k] / b[k];  // a zero divisor leaves the channel
            break;
        case 6: r = interp(a, glm::abs(a - b), t); break;
        case 7: r = interp(a, cmin(a, b), t); break;
        case 8: r = interp(a, cmax(a, b), t); break;
        case 9: r = {overlay(a.x, b.x, t), overlay(a.y, b.y, t), overlay(a.z, b.z, t)}; break;
        case 10: r = {dodge(a.x, b.x, t), dodge(a.y, b.y, t), dodge(a.z, b.z, t)}; break;
        case 11: r = {burn(a.x, b.x, t), burn(a.y, b.y, t), burn(a.z, b.z, t)}; break;
        case 12: {  // hue of b (a grey b has none: a is kept)
            const glm::vec3 hsv_b = rgb_to_hsv(b);
            r = a;
            if (hsv_b.y != 0.0f) {
                glm::vec3 hsv = rgb_to_hsv(a);
                hsv.x = hsv_b.x;
                r = interp(a, hsv_to_rgb(hsv), t);
            }
            break;
        }
        case 13: {  // saturation towards b's (a grey a stays grey)
            glm::vec3 hsv = rgb_to_hsv(a);
            r = a;
            if (hsv.y != 0.0f) {
                hsv.y = tm * hsv.y + t * rgb_to_hsv(b).y;
                r = hsv_to_rgb(hsv);
            }
            break;
        }
        case 14: {
            glm::vec3 hsv = rgb_to_hsv(a);
            hsv.z = tm * hsv.z + t * rgb_to_hsv(b).z;
            r = hsv_to_rgb(hsv);
            break;
        }
        case 15: {  // hue and saturation of b
            const glm::vec3 hsv_b = rgb_to_hsv(b);
            r = a;
            if (hsv_b.y != 0.0f) {
                glm::vec3 hsv = rgb_to_hsv(a);
                hsv.x = hsv_b.x;
                hsv.y = hsv_b.y;
                r = interp(a, hsv_to_rgb(hsv), t);
            }
            break;
        }
        case 16: {
            const glm::vec3 screen = one - (one - b) * (one - a);
            r = tm * a + t * ((one - a) * b * a + a * screen);
            break;
        }
        case 17: r = a + t * (2.0f * b + glm::vec3(-1.0f)); break;
        case 18: r = csaturate(a); break;
        default: return false;
    }
    return true;
}

// --- Blackbody and Wavelength ------------------------------------------------------------------------------------

// Cycles 3.4's fit of the Planckian locus in Rec.709 (kernel/tables.h, data): R and G as a/T + bT + c, B as a
// cubic in T, over seven temperature bands from 800 K to 12000 K.
constexpr float kBlackbodyR[7][3] = {
    {1.61919106e+03f, -2.05010916e-03f, 5.02995757e+00f}, {2.48845471e+03f, -1.11330907e-03f, 3.22621544e+00f},
    {3.34143193e+03f, -4.86551192e-04f, 1.76486769e+00f}, {4.09461742e+03f, -1.27446582e-04f, 7.25731635e-01f},
    {4.67028036e+03f, 2.91258199e-05f, 1.26703442e-01f},  {4.59509185e+03f, 2.87495649e-05f, 1.50345020e-01f},
    {3.78717450e+03f, 9.35907826e-06f, 3.99075871e-01f}};
constexpr float kBlackbodyG[7][3] = {
    {-4.88999748e+02f, 6.04330754e-04f, -7.55807526e-02f}, {-7.55994277e+02f, 3.16730098e-04f, 4.78306139e-01f},
    {-1.02363977e+03f, 1.20223470e-04f, 9.36662319e-01f},  {-1.26571316e+03f, 4.87340896e-06f, 1.27054498e+00f},
    {-1.42529332e+03f, -4.01150431e-05f, 1.43972784e+00f}, {-1.17554822e+03f, -2.16378048e-05f, 1.30408023e+00f},
    {-5.00799571e+02f, -4.59832026e-06f, 1.09098763e+00f}};
constexpr float kBlackbodyB[7][4] = {
    {5.96945309e-11f, -4.85742887e-08f, -9.70622247e-05f, -4.07936148e-03f},
    {2.40430366e-11f, 5.55021075e-08f, -1.98503712e-04f, 2.89312858e-02f},
    {-1.40949732e-11f, 1.89878968e-07f, -3.56632824e-04f, 9.10767778e-02f},
    {-3.61460868e-11f, 2.84822009e-07f, -4.93211319e-04f, 1.56723440e-01f},
    {-1.97075738e-11f, 1.75359352e-07f, -2.50542825e-04f, -2.22783266e-02f},
    {-1.61997957e-13f, -1.64216008e-08f, 3.86216271e-04f, -7.38077418e-01f},
    {6.72650283e-13f, -2.73078809e-08f, 4.24098264e-04f, -7.52335691e-01f}};

glm::vec3 blackbody(float t) {
    glm::vec3 c;
    if (t >= 12000.0f) {
        c = {0.8262954810464208f, 0.9945080501520986f, 1.566307710274283f};
    } else if (t < 800.0f) {
        c = {5.413294490189271f, -0.20319390035873933f, -0.0822535242887164f};  // dim; held, as OSL does
    } else {
        const int i = t >= 6365.0f ? 6 : t >= 3315.0f ? 5 : t >= 1902.0f ? 4 : t >= 1449.0f ? 3
                    : t >= 1167.0f ? 2 : t >= 965.0f ? 1 : 0;  // NaN falls to band 0 and stays NaN
        const float* r = kBlackbodyR[i];
        const float* g = kBlackbodyG[i];
        const float* b = kBlackbodyB[i];
        const float t_inv = 1.0f / t;
        c = {r[0] * t_inv + r[1] * t + r[2], g[0] * t_inv + g[1] * t + g[2], ((b[0] * t + b[1]) * t + b[2]) * t + b[3]};
    }
    // The fit is Rec.709, which is Blender 3.4's scene-linear space (Cycles' is_rec709); out-of-gamut negatives
    // are cut (a NaN too, by Cycles' max).
    return cmax(c, glm::vec3(0.0f));
}

// CIE 1931 colour matching functions x̄, ȳ, z̄ at 380, 385, ..., 780 nm: Cycles 3.4's cie_colour_match
// (kernel/tables.h), data.
constexpr float kCieColourMatch[81][3] = {
    {0.0014f, 0.0000f, 0.0065f}, {0.0022f, 0.0001f, 0.0105f}, {0.0042f, 0.0001f, 0.0201f},
    {0.0076f, 0.0002f, 0.0362f}, {0.0143f, 0.0004f, 0.0679f}, {0.0232f, 0.0006f, 0.1102f},
    {0.0435f, 0.0012f, 0.2074f}, {0.0776f, 0.0022f, 0.3713f}, {0.1344f, 0.0040f, 0.6456f},
    {0.2148f, 0.0073f, 1.0391f}, {0.2839f, 0.0116f, 1.3856f}, {0.3285f, 0.0168f, 1.6230f},
    {0.3483f, 0.0230f, 1.7471f}, {0.3481f, 0.0298f, 1.7826f}, {0.3362f, 0.0380f, 1.7721f},
    {0.3187f, 0.0480f, 1.7441f}, {0.2908f, 0.0600f, 1.6692f}, {0.2511f, 0.0739f, 1.5281f},
    {0.1954f, 0.0910f, 1.2876f}, {0.1421f, 0.1126f, 1.0419f}, {0.0956f, 0.1390f, 0.8130f},
    {0.0580f, 0.1693f, 0.6162f}, {0.0320f, 0.2080f, 0.4652f}, {0.0147f, 0.2586f, 0.3533f},
    {0.0049f, 0.3230f, 0.2720f}, {0.0024f, 0.4073f, 0.2123f}, {0.0093f, 0.5030f, 0.1582f},
    {0.0291f, 0.6082f, 0.1117f}, {0.0633f, 0.7100f, 0.0782f}, {0.1096f, 0.7932f, 0.0573f},
    {0.1655f, 0.8620f, 0.0422f}, {0.2257f, 0.9149f, 0.0298f}, {0.2904f, 0.9540f, 0.0203f},
    {0.3597f, 0.9803f, 0.0134f}, {0.4334f, 0.9950f, 0.0087f}, {0.5121f, 1.0000f, 0.0057f},
    {0.5945f, 0.9950f, 0.0039f}, {0.6784f, 0.9786f, 0.0027f}, {0.7621f, 0.9520f, 0.0021f},
    {0.8425f, 0.9154f, 0.0018f}, {0.9163f, 0.8700f, 0.0017f}, {0.9786f, 0.8163f, 0.0014f},
    {1.0263f, 0.7570f, 0.0011f}, {1.0567f, 0.6949f, 0.0010f}, {1.0622f, 0.6310f, 0.0008f},
    {1.0456f, 0.5668f, 0.0006f}, {1.0026f, 0.5030f, 0.0003f}, {0.9384f, 0.4412f, 0.0002f},
    {0.8544f, 0.3810f, 0.0002f}, {0.7514f, 0.3210f, 0.0001f}, {0.6424f, 0.2650f, 0.0000f},
    {0.5419f, 0.2170f, 0.0000f}, {0.4479f, 0.1750f, 0.0000f}, {0.3608f, 0.1382f, 0.0000f},
    {0.2835f, 0.1070f, 0.0000f}, {0.2187f, 0.0816f, 0.0000f}, {0.1649f, 0.0610f, 0.0000f},
    {0.1212f, 0.0446f, 0.0000f}, {0.0874f, 0.0320f, 0.0000f}, {0.0636f, 0.0232f, 0.0000f},
    {0.0468f, 0.0170f, 0.0000f}, {0.0329f, 0.0119f, 0.0000f}, {0.0227f, 0.0082f, 0.0000f},
    {0.0158f, 0.0057f, 0.0000f}, {0.0114f, 0.0041f, 0.0000f}, {0.0081f, 0.0029f, 0.0000f},
    {0.0058f, 0.0021f, 0.0000f}, {0.0041f, 0.0015f, 0.0000f}, {0.0029f, 0.0010f, 0.0000f},
    {0.0020f, 0.0007f, 0.0000f}, {0.0014f, 0.0005f, 0.0000f}, {0.0010f, 0.0004f, 0.0000f},
    {0.0007f, 0.0002f, 0.0000f}, {0.0005f, 0.0002f, 0.0000f}, {0.0003f, 0.0001f, 0.0000f},
    {0.0002f, 0.0001f, 0.0000f}, {0.0002f, 0.0001f, 0.0000f}, {0.0001f, 0.0000f, 0.0000f},
    {0.0001f, 0.0000f, 0.0000f}, {0.0001f, 0.0000f, 0.0000f}, {0.0000f, 0.0000f, 0.0000f}};

glm::vec3 wavelength(float lambda_nm) {
    // Table position; Cycles truncates towards zero, so 375..380 nm reads interval 0 with a negative fraction
    // (extrapolating), and 780 nm itself and above are black, as is anything below 375 nm.
    float ii = (lambda_nm - 380.0f) * (1.0f / 5.0f);
    const int i = float_to_int(ii);
    glm::vec3 xyz(0.0f);
    if (i >= 0 && i < 80) {
        ii -= static_cast<float>(i);
        const float* c0 = kCieColourMatch[i];
        const float* c1 = kCieColourMatch[i + 1];
        xyz = interp(glm::vec3(c0[0], c0[1], c0[2]), glm::vec3(c1[0], c1[1], c1[2]), ii);
    }
    // Cycles' empirical 1/2.52 keeps every component of the spectrum's colours at or below 1; the negative
    // (out-of-gamut) parts are cut.
    glm::vec3 rgb = xyz_to_rgb(xyz) * (1.0f / 2.52f);
    return cmax(rgb, glm::vec3(0.0f));
}

// --- Mapping and Vector Rotate -----------------------------------------------------------------------------------

// Blender's XYZ euler rotation (X first, then Y, then Z) as the rows of a matrix: R v = (row0·v, row1·v, row2·v).
struct Rows {
    glm::vec3 r[3];
    glm::vec3 apply(const glm::vec3& v) const { return {glm::dot(r[0], v), glm::dot(r[1], v), glm::dot(r[2], v)}; }
    glm::vec3 apply_transposed(const glm::vec3& v) const {
        return r[0] * v.x + r[1] * v.y + r[2] * v.z;
    }
};

Rows euler_xyz(const glm::vec3& e) {
    const float cx = std::cos(e.x), cy = std::cos(e.y), cz = std::cos(e.z);
    const float sx = std::sin(e.x), sy = std::sin(e.y), sz = std::sin(e.z);
    Rows m;
    m.r[0] = {cy * cz, sy * sx * cz - cx * sz, sy * cx * cz + sx * sz};
    m.r[1] = {cy * sz, sy * sx * sz + cx * cz, sy * cx * sz - sx * cz};
    m.r[2] = {-sy, cy * sx, cy * cx};
    return m;
}

bool mapping(int type, const glm::vec3& v, const glm::vec3& loc, const glm::vec3& rot, const glm::vec3& scale,
             glm::vec3& r) {
    const Rows m = euler_xyz(rot);
    switch (type) {
        case 0: r = m.apply(v * scale) + loc; break;                                  // point
        case 1: r = safe_divide(m.apply_transposed(v - loc), scale); break;          // texture: the inverse
        case 2: r = m.apply(v * scale); break;                                        // vector: no translation
        case 3: r = safe_normalize(m.apply(safe_divide(v, scale))); break;            // normal: inverse transpose
        default: return false;
    }
    return true;
}

// Rodrigues' rotation of p about the unit axis, written out as Cycles writes it.
glm::vec3 rotate_around_axis(const glm::vec3& p, const glm::vec3& axis, float angle) {
    const float c = std::cos(angle), s = std::sin(angle), ic = 1.0f - c;
    return {(c + ic * axis.x * axis.x) * p.x + (ic * axis.x * axis.y - axis.z * s) * p.y +
                (ic * axis.x * axis.z + axis.y * s) * p.z,
            (ic * axis.x * axis.y + axis.z * s) * p.x + (c + ic * axis.y * axis.y) * p.y +
                (ic * axis.y * axis.z - axis.x * s) * p.z,
            (ic * axis.x * axis.z - axis.y * s) * p.x + (ic * axis.y * axis.z + axis.x * s) * p.y +
                (c + ic * axis.z * axis.z) * p.z};
}

bool vector_rotate(int type, bool invert, const glm::vec3& v, const glm::vec3& center, const glm::vec3& axis_in,
                   float angle, const glm::vec3& rotation, glm::vec3& r) {
    if (type < 0 || type > 4) return false;
    if (type == 4) {
        const Rows m = euler_xyz(rotation);
        r = (invert ? m.apply_transposed(v - center) : m.apply(v - center)) + center;
        return true;
    }
    glm::vec3 axis = type == 1 ? glm::vec3(1, 0, 0) : type == 2 ? glm::vec3(0, 1, 0) : type == 3 ? glm::vec3(0, 0, 1)
                                                                                                : axis_in;
    const float len = type == 0 ? glm::length(axis) : 1.0f;
    if (invert) angle = -angle;
    // A zero axis has no rotation: the vector passes unchanged (not even about the centre).
    r = len != 0.0f ? rotate_around_axis(v - center, axis / len, angle) + center : v;
    return true;
}

bool in01(int p) { return p == 0 || p == 1; }

}  // namespace

bool run_converter_op(ShaderOp op, const OpArgs& a, const float* tables) {
    const glm::vec3 zero(0.0f);
    switch (op) {
        case ShaderOp::math: {
            float r = 0.0f;
            if (!in01(a.param(1)) || !math(a.param(0), a.f(0), a.f(1), a.f(2), r)) r = 0.0f;
            else if (a.param(1)) r = cclamp(r, 0.0f, 1.0f);  // Cycles adds a Clamp node (0..1)
            a.set(0, r);
            return true;
        }
        case ShaderOp::vector_math: {
            float value = 0.0f;
            glm::vec3 vector(0.0f);
            if (!vector_math(a.param(0), a.v(0), a.v(1), a.v(2), a.f(3), value, vector)) {
                value = 0.0f;
                vector = zero;
            }
            a.set(0, vector);
            a.set(1, value);
            return true;
        }
        case ShaderOp::map_range: {
            float r = 0.0f;
            if (!in01(a.param(1)) ||
                !map_range(a.param(0), a.param(1) != 0, a.f(0), a.f(1), a.f(2), a.f(3), a.f(4), a.f(5), r))
                r = 0.0f;
            a.set(0, r);
            return true;
        }
        case ShaderOp::map_range_vector: {
            glm::vec3 r(0.0f);
            if (!in01(a.param(1)) ||
                !map_range_vector(a.param(0), a.param(1) != 0, a.v(0), a.v(1), a.v(2), a.v(3), a.v(4), a.v(5), r))
                r = zero;
            a.set(0, r);
            return true;
        }
        case ShaderOp::clamp:
            a.set(0, in01(a.param(0)) ? clamp_node(a.f(0), a.f(1), a.f(2), a.param(0) == 1) : 0.0f);
            return true;
        case ShaderOp::color_ramp: {
            const int offset = a.param(0), n = a.param(1);
            if (!tables || offset < 0 || n < 1 || !in01(a.param(2))) {
                a.set(0, zero);
                a.set(1, 0.0f);
                return true;
            }
            const float* t = tables + offset;
            const float fac = a.f(0);
            const bool lerp = a.param(2) == 1;
            a.set(0, glm::vec3(table_lookup(t, n, 4, fac, lerp, false), table_lookup(t + 1, n, 4, fac, lerp, false),
                               table_lookup(t + 2, n, 4, fac, lerp, false)));
            a.set(1, table_lookup(t + 3, n, 4, fac, lerp, false));
            return true;
        }
        case ShaderOp::rgb_curves:
        case ShaderOp::vector_curves: {
            const int offset = a.param(0), n = a.param(1);
            if (!tables || offset < 0 || n < 2) {
                a.set(0, zero);
                return true;
            }
            const float* t = tables + offset;
            const float fac = a.f(0);
            const glm::vec3 in = a.v(1);
            const float min_x = t[0], range_x = t[1] - t[0];
            // Cycles divides unguarded: a zero range gives ±inf or NaN positions, which the lookup handles.
            glm::vec3 curve;
            for (int k = 0; k < 3; ++k)
                curve[k] = table_lookup(t + 2 + k, n, 3, (in[k] - min_x) / range_x, true, kCurvesExtrapolate);
            a.set(0, (1.0f - fac) * in + fac * curve);
            return true;
        }
        case ShaderOp::float_curve: {
            const int offset = a.param(0), n = a.param(1);
            if (!tables || offset < 0 || n < 2) {
                a.set(0, 0.0f);
                return true;
            }
            const float* t = tables + offset;
            const float fac = a.f(0), in = a.f(1);
            const float v = table_lookup(t + 2, n, 1, (in - t[0]) / (t[1] - t[0]), true, kCurvesExtrapolate);
            a.set(0, (1.0f - fac) * in + fac * v);
            return true;
        }
        case ShaderOp::mix_color: {
            glm::vec3 r(0.0f);
            float t = a.f(0);
            if (a.param(1) == 1) t = csaturate(t);
            if (!in01(a.param(1)) || !in01(a.param(2)) || !mix_blend(a.param(0), t, a.v(1), a.v(2), r)) r = zero;
            else if (a.param(2) == 1) r = csaturate(r);
            a.set(0, r);
            return true;
        }
        case ShaderOp::mix_float: {
            if (!in01(a.param(0))) {
                a.set(0, 0.0f);
                return true;
            }
            const float t = a.param(0) ? csaturate(a.f(0)) : a.f(0);
            a.set(0, a.f(1) * (1.0f - t) + a.f(2) * t);
            return true;
        }
        case ShaderOp::mix_vector: {
            if (!in01(a.param(0))) {
                a.set(0, zero);
                return true;
            }
            const float t = a.param(0) ? csaturate(a.f(0)) : a.f(0);
            a.set(0, a.v(1) * (1.0f - t) + a.v(2) * t);
            return true;
        }
        case ShaderOp::mix_vector_nonuniform: {
            if (!in01(a.param(0))) {
                a.set(0, zero);
                return true;
            }
            const glm::vec3 t = a.param(0) ? csaturate(a.v(0)) : a.v(0);
            a.set(0, a.v(1) * (glm::vec3(1.0f) - t) + a.v(2) * t);
            return true;
        }
        case ShaderOp::hue_saturation_value: {
            const float hue = a.f(0), sat = a.f(1), val = a.f(2), fac = a.f(3);
            const glm::vec3 in = a.v(4);
            glm::vec3 hsv = rgb_to_hsv(in);
            // The hue input is an offset with 0.5 meaning none; fmod keeps a negative sum negative, as Cycles does.
            hsv.x = std::fmod(hsv.x + hue + 0.5f, 1.0f);
            hsv.y = csaturate(hsv.y * sat);
            hsv.z *= val;
            const glm::vec3 c = hsv_to_rgb(hsv);
            glm::vec3 r = fac * c + (1.0f - fac) * in;
            a.set(0, cmax(r, zero));  // over-saturation can go negative; Cycles cuts it
            return true;
        }
        case ShaderOp::gamma: {
            glm::vec3 c = a.v(0);
            const float g = a.f(1);
            if (g == 0.0f) {
                c = glm::vec3(1.0f);
            } else {
                for (int k = 0; k < 3; ++k)
                    if (c[k] > 0.0f) c[k] = std::pow(c[k], g);  // non-positive channels pass unchanged
            }
            a.set(0, c);
            return true;
        }
        case ShaderOp::bright_contrast: {
            const glm::vec3 c = a.v(0);
            const float bright = a.f(1), contrast = a.f(2);
            // Contrast pivots about 0.5: slope 1 + contrast, offset so that 0.5 maps to 0.5 + bright.
            const float m = 1.0f + contrast, b = bright - contrast * 0.5f;
            a.set(0, glm::vec3(cmax(m * c.x + b, 0.0f), cmax(m * c.y + b, 0.0f), cmax(m * c.z + b, 0.0f)));
            return true;
        }
        case ShaderOp::invert: {
            const float fac = a.f(0);
            const glm::vec3 c = a.v(1);
            a.set(0, fac * (glm::vec3(1.0f) - c) + (1.0f - fac) * c);
            return true;
        }
        case ShaderOp::separate_color: {
            const int mode = a.param(0);
            glm::vec3 c = a.v(0);
            if (mode == 1) c = rgb_to_hsv(c);
            else if (mode == 2) c = rgb_to_hsl(c);
            else if (mode != 0) c = zero;
            a.set(0, c.x);
            a.set(1, c.y);
            a.set(2, c.z);
            return true;
        }
        case ShaderOp::combine_color: {
            const int mode = a.param(0);
            glm::vec3 c(a.f(0), a.f(1), a.f(2));
            if (mode == 1) c = hsv_to_rgb(c);
            else if (mode == 2) c = hsl_to_rgb(c);
            else if (mode != 0) c = zero;
            a.set(0, c);
            return true;
        }
        case ShaderOp::rgb_to_bw:
            a.set(0, cycles_luminance(a.v(0)));
            return true;
        case ShaderOp::blackbody:
            a.set(0, blackbody(a.f(0)));
            return true;
        case ShaderOp::wavelength:
            a.set(0, wavelength(a.f(0)));
            return true;
        case ShaderOp::mapping: {
            glm::vec3 r(0.0f);
            if (!mapping(a.param(0), a.v(0), a.v(1), a.v(2), a.v(3), r)) r = zero;
            a.set(0, r);
            return true;
        }
        case ShaderOp::vector_rotate: {
            glm::vec3 r(0.0f);
            if (!in01(a.param(1)) ||
                !vector_rotate(a.param(0), a.param(1) == 1, a.v(0), a.v(1), a.v(2), a.f(3), a.v(4), r))
                r = zero;
            a.set(0, r);
            return true;
        }
        default:
            return false;
    }
}

}  // namespace ps
