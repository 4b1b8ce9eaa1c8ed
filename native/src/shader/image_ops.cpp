// Image Texture and Environment Texture nodes: the texture coordinate turned into an image position by the
// node's projection, then Texture::sample (Cycles 3.4's svm/image.h and camera/projection.h).
#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "photonsplat/scene.h"
#include "shader/op_args.h"

namespace ps {

namespace {

constexpr float kPi = 3.14159265358979323846f;

TextureInterpolation interpolation_of(int param) {
    switch (param) {
        case 1: return TextureInterpolation::closest;
        case 2:
        case 3: return TextureInterpolation::cubic;  // Smart is cubic on CPUs
        default: return TextureInterpolation::linear;
    }
}

TextureExtension extension_of(int param) {
    switch (param) {
        case 1: return TextureExtension::extend;
        case 2: return TextureExtension::clip;
        case 3: return TextureExtension::mirror;
        default: return TextureExtension::repeat;
    }
}

TextureAlpha alpha_of(int param) {
    switch (param) {
        case 1: return TextureAlpha::associated;
        case 2: return TextureAlpha::channel_packed;
        default: return TextureAlpha::unassociated;
    }
}

// Sphere and tube projections of a point in the [-1, 1] box (Cycles' map_to_sphere, map_to_tube).
glm::vec2 map_to_sphere(const glm::vec3& co) {
    const float l = glm::dot(co, co);
    if (!(l > 0.0f)) return glm::vec2(0.0f);
    const float u = (co.x == 0.0f && co.y == 0.0f) ? 0.0f : 0.5f - std::atan2(co.x, co.y) / (2.0f * kPi);
    const float v = 1.0f - std::acos(std::clamp(co.z / std::sqrt(l), -1.0f, 1.0f)) / kPi;
    return glm::vec2(u, v);
}

glm::vec2 map_to_tube(const glm::vec3& co) {
    const float len = std::sqrt(co.x * co.x + co.y * co.y);
    if (!(len > 0.0f)) return glm::vec2(0.0f);
    return glm::vec2((1.0f - std::atan2(co.x / len, co.y / len) / kPi) * 0.5f, (co.z + 1.0f) * 0.5f);
}

// Box projection: the weights of the three axis-aligned planar projections from the object-space normal, blended
// over `blend` of the way between them (the seven zones of Cycles' svm_node_tex_image_box).
glm::vec3 box_weights(glm::vec3 n, float blend) {
    n = glm::abs(n);
    const float sum = n.x + n.y + n.z;
    if (!(sum > 0.0f)) return glm::vec3(1.0f, 0.0f, 0.0f);
    n /= sum;
    const float limit = 0.5f * (1.0f + blend);
    glm::vec3 w(0.0f);
    if (n.x > limit * (n.x + n.y) && n.x > limit * (n.x + n.z)) {
        w.x = 1.0f;
    } else if (n.y > limit * (n.x + n.y) && n.y > limit * (n.y + n.z)) {
        w.y = 1.0f;
    } else if (n.z > limit * (n.x + n.z) && n.z > limit * (n.y + n.z)) {
        w.z = 1.0f;
    } else if (blend > 0.0f) {
        const auto ramp = [&](float t) { return std::clamp((t - 0.5f * (1.0f - blend)) / blend, 0.0f, 1.0f); };
        if (n.z < (1.0f - limit) * (n.y + n.x)) {
            w.x = ramp(n.x / (n.x + n.y));
            w.y = 1.0f - w.x;
        } else if (n.x < (1.0f - limit) * (n.y + n.z)) {
            w.y = ramp(n.y / (n.y + n.z));
            w.z = 1.0f - w.y;
        } else if (n.y < (1.0f - limit) * (n.x + n.z)) {
            w.x = ramp(n.x / (n.x + n.z));
            w.z = 1.0f - w.x;
        } else {  // all three
            w = ((2.0f - limit) * n + (limit - 1.0f)) / (2.0f * limit - 1.0f);
        }
    } else {
        w.x = 1.0f;  // no blend and no clear winner: one side, as Cycles
    }
    return w;
}

}  // namespace

bool run_image_op(ShaderOp op, const OpArgs& a, const Scene& scene, const ShaderGlobals& g) {
    if (op != ShaderOp::image_texture && op != ShaderOp::environment_texture) return false;
    const int32_t index = a.param(0);
    if (index < 0 || static_cast<size_t>(index) >= scene.textures().size()) {  // validated; never in practice
        a.set(0, glm::vec3(0.0f));
        a.set(1, 0.0f);
        return true;
    }
    const Texture& texture = scene.textures()[static_cast<size_t>(index)];
    const TextureInterpolation interpolation = interpolation_of(a.param(1));
    glm::vec4 c(0.0f);
    if (op == ShaderOp::environment_texture) {
        glm::vec3 d = a.v(0);
        const float len = glm::length(d);
        d = len > 0.0f && std::isfinite(len) ? d / len : glm::vec3(0.0f);
        glm::vec2 uv(0.0f);
        if (a.param(2) == 1) {  // mirror ball
            glm::vec3 m = d;
            m.y -= 1.0f;
            const float div = 2.0f * std::sqrt(std::max(-0.5f * m.y, 0.0f));
            if (div > 0.0f) m /= div;
            uv = glm::vec2(0.5f * (m.x + 1.0f), 0.5f * (m.z + 1.0f));
        } else if (d != glm::vec3(0.0f)) {  // equirectangular: u from the azimuth (−X at the centre), v up
            uv = glm::vec2(0.5f - std::atan2(d.y, d.x) / (2.0f * kPi),
                           1.0f - std::acos(std::clamp(d.z, -1.0f, 1.0f)) / kPi);
        }
        c = texture.sample(uv.x, uv.y, interpolation, TextureExtension::repeat, TextureAlpha::unassociated);
    } else {
        const TextureExtension extension = extension_of(a.param(2));
        const TextureAlpha alpha = alpha_of(a.param(4));
        const glm::vec3 co = a.v(0);
        switch (a.param(3)) {
            case 1: {  // box: three planar projections weighted by the object-space normal
                const glm::vec3 n = glm::transpose(g.object_to_world_linear) * g.N;
                const glm::vec3 w = box_weights(n, std::clamp(a.f(1), 0.0f, 1.0f));
                if (w.x > 0.0f)
                    c += w.x * texture.sample(n.x < 0.0f ? 1.0f - co.y : co.y, co.z, interpolation, extension, alpha);
                if (w.y > 0.0f)
                    c += w.y * texture.sample(n.y > 0.0f ? 1.0f - co.x : co.x, co.z, interpolation, extension, alpha);
                if (w.z > 0.0f)
                    c += w.z * texture.sample(n.z > 0.0f ? 1.0f - co.y : co.y, co.x, interpolation, extension, alpha);
                break;
            }
            case 2: {
                const glm::vec2 uv = map_to_sphere((co - 0.5f) * 2.0f);
                c = texture.sample(uv.x, uv.y, interpolation, extension, alpha);
                break;
            }
            case 3: {
                const glm::vec2 uv = map_to_tube((co - 0.5f) * 2.0f);
                c = texture.sample(uv.x, uv.y, interpolation, extension, alpha);
                break;
            }
            default: c = texture.sample(co.x, co.y, interpolation, extension, alpha); break;
        }
    }
    a.set(0, glm::vec3(c));
    a.set(1, c.w);
    return true;
}

}  // namespace ps
