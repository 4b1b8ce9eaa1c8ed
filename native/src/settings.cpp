#include "photonsplat/settings.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <type_traits>

#include "photonsplat/errors.h"

namespace ps {

namespace {

constexpr double kMaxPhotons = 500'000'000;  // ~40 GB of photon records: beyond any machine we target
constexpr double kMaxIterations = 1'000'000;  // r shrinks as iterations^(−1/6): far past any useful radius
constexpr double kMaxTimeLimit = 1e7;         // seconds, about 4 months

std::optional<SettingBound> inclusive(double value) { return SettingBound{value, false}; }
std::optional<SettingBound> exclusive(double value) { return SettingBound{value, true}; }
constexpr std::nullopt_t none = std::nullopt;

// A row without a range or a note: a switch, a choice, a set, or a number every value of which is valid.
Setting unbounded(const char* name, SettingMember member, const char* description) {
    return {name, member, none, none, SettingUnit::none, "", description};
}

// --- enumerations: the names of their choices, in the enum's order ------------------------------------------

std::vector<std::string> choice_names(SplatMethod) { return splat_method_names(); }
std::vector<std::string> choice_names(Kernel) { return {to_string(Kernel::uniform), to_string(Kernel::epanechnikov)}; }

std::vector<std::string> choice_names(FilmOutputSet) { return film_output_names(kAllFilmOutputs); }

SplatMethod from_choice(SplatMethod, const std::string& name) { return splat_method_from_string(name); }
Kernel from_choice(Kernel, const std::string& name) { return kernel_from_string(name); }

template <typename T>
constexpr SettingType type_of() {
    if constexpr (std::is_same_v<T, bool>) return SettingType::boolean;
    else if constexpr (std::is_same_v<T, FilmOutputSet>) return SettingType::set;
    else if constexpr (std::is_enum_v<T>) return SettingType::enumeration;
    else if constexpr (std::is_same_v<T, float>) return SettingType::float_;
    else if constexpr (std::is_same_v<T, double>) return SettingType::double_;
    else if constexpr (std::is_unsigned_v<T>) return SettingType::uint;
    else return SettingType::int_;
}

// A bound as messages write it: integers in full, other values as printf's %g.
std::string number(double value) {
    char text[64];
    if (std::floor(value) == value && std::fabs(value) < 1e18) std::snprintf(text, sizeof text, "%.0f", value);
    else std::snprintf(text, sizeof text, "%g", value);
    return text;
}

std::string describe(const SettingValue& value) {
    return std::visit(
        [](const auto& v) -> std::string {
            using V = std::decay_t<decltype(v)>;
            if constexpr (std::is_same_v<V, std::string>) return "'" + v + "'";
            else if constexpr (std::is_same_v<V, std::vector<std::string>>) {
                std::string names;
                for (const std::string& name : v) names += (names.empty() ? "'" : ", '") + name + "'";
                return "(" + names + ")";
            }
            else if constexpr (std::is_same_v<V, bool>) return v ? "true" : "false";
            else return std::to_string(v);
        },
        value);
}

const char* kind_of(const SettingValue& value) {
    static const char* const kinds[] = {"a bool", "an integer", "an integer", "a number", "a string", "a list of names"};
    return kinds[value.index()];
}

}  // namespace

const std::vector<Setting>& render_settings_table() {
    using S = RenderSettings;
    using U = SettingUnit;
    static const std::vector<Setting> table = {
        {"photons", &S::photons, none, inclusive(kMaxPhotons), U::none, "",
         "Photon paths traced from the lights per iteration: more photons give less noise in indirect light and "
         "caustics"},
        {"radius", &S::radius, inclusive(0), none, U::length, "0 = automatic",
         "Splatting radius of each photon in world units; 0 chooses it from the size of the scene and the photon "
         "count"},
        unbounded("method", &S::method, "How photons are splatted onto the pixels they light"),
        {"max_bounces", &S::max_bounces, inclusive(0), inclusive(1000), U::none, "",
         "Longest photon path, and the deepest chain of mirror/glass bounces followed from the camera"},
        unbounded("seed", &S::seed,
         "Random seed; the same seed gives the same image whatever the number of threads"),
        {"threads", &S::threads, inclusive(0), inclusive(4096), U::none, "0 = all cores",
         "Number of CPU threads; 0 uses all cores"},
        {"direct_samples", &S::direct_samples, inclusive(1), inclusive(4096), U::none, "",
         "Shadow rays per light and pixel for direct light (soft shadows of lights with a size)"},
        {"normal_tolerance", &S::normal_tolerance, exclusive(0), inclusive(180), U::degrees, "",
         "Photons on surfaces turned further than this from a pixel's surface are ignored"},
        {"plane_distance", &S::plane_distance, inclusive(0), none, U::none, "0 = off",
         "Photons farther from a pixel's surface plane than this many radii are ignored (stacked surfaces); 0 = off"},
        unbounded("kernel", &S::kernel,
         "Density-estimation kernel: how a photon's light is spread over its radius"),
        unbounded("boundary_correction", &S::boundary_correction,
         "Divide each pixel's bounced light by the part of its kernel that lies on a surface like its own, so "
         "corners, edges and thin parts are not darkened (glossy surfaces and Directional's approximate iterations "
         "excepted); off gives the paper's plain estimate"),
        unbounded("adaptive_radius", &S::adaptive_radius,
         "Photons that gather far more densely than usual (focused caustics) splat with a half or a quarter of the "
         "radius, so that each disc holds about as many photons as a usual one: sharper caustics at the same "
         "noise; off splats every photon with one radius"),
        {"directional_level", &S::directional_level, inclusive(-1), inclusive(64), U::none, "-1 = chosen from the radius",
         "Directional method only: hierarchy level (from the leaves) where photons stop; -1 chooses it from the "
         "radius"},
        {"memory_budget", &S::memory_budget, none, none, U::bytes, "0 = 3/4 of available memory",
         "Memory a render may hold; a render whose structures would not fit is refused before allocating, naming "
         "what to lower; 0 uses three quarters of this machine's memory"},
        unbounded("guide_photons", &S::guide_photons,
         "Emit sun photons where pilot paths found them stored, weighted so that the image stays unbiased"),
        {"aimed_photons", &S::aimed_photons, inclusive(0), inclusive(16), U::none, "a fraction of photons; 0 = off",
         "Extra photons per iteration aimed at mirror and glass objects from point, spot and area lights, as a "
         "fraction of photons; they add caustic photons only, weighted so that the image stays unbiased; 0 = off"},
        unbounded("outputs", &S::outputs,
         "The images the render produces (combined always): fewer hold less memory, above all in a progressive "
         "render's running sums"),
        unbounded("caustics_pass", &S::caustics_pass,
         "Also splat the caustic photons (light, then mirrors/glass, then a diffuse surface) alone into a caustics "
         "image"),
        unbounded("transparent", &S::transparent,
         "Film transparency: alpha 0 and no background where camera rays escape to the world"),
        {"iterations", &S::iterations, inclusive(0), inclusive(kMaxIterations), U::none, "0 = until time_limit",
         "Progressive iterations, each with new photons, a smaller radius and jittered pixels, averaged: 1 = the "
         "one-shot method, 0 = as many as fit in the time limit",
         {"passes"}},
        {"time_limit", &S::time_limit, inclusive(0), inclusive(kMaxTimeLimit), U::seconds, "0 = none",
         "Seconds of progressive rendering (no iteration is started that would end past it); 0 = no limit"},
        {"alpha", &S::alpha, exclusive(0), inclusive(1), U::none, "2/3 balances noise and blur; 1 keeps the radius fixed",
         "Radius shrink over iterations, r_i^2 = r_(i-1)^2 (i-1+alpha)/i, in (0, 1]: 2/3 balances noise and blur, "
         "1 keeps the radius fixed"},
    };
    return table;
}

const Setting* find_setting(const std::string& name) {
    for (const Setting& row : render_settings_table()) {
        if (name == row.name) return &row;
        for (const std::string& alias : row.aliases)
            if (name == alias) return &row;
    }
    return nullptr;
}

const char* to_string(SettingType type) {
    switch (type) {
        case SettingType::uint: return "uint";
        case SettingType::int_: return "int";
        case SettingType::float_: return "float";
        case SettingType::double_: return "double";
        case SettingType::boolean: return "bool";
        case SettingType::enumeration: return "enum";
        case SettingType::set: return "set";
    }
    return "";
}

const char* to_string(SettingUnit unit) {
    switch (unit) {
        case SettingUnit::none: return "";
        case SettingUnit::length: return "length";
        case SettingUnit::degrees: return "degrees";
        case SettingUnit::seconds: return "seconds";
        case SettingUnit::bytes: return "bytes";
    }
    return "";
}

SettingType Setting::type() const {
    return std::visit([](auto member) { return type_of<std::decay_t<decltype(RenderSettings{}.*member)>>(); }, this->member);
}

std::vector<std::string> Setting::choices() const {
    return std::visit(
        [](auto member) -> std::vector<std::string> {
            using T = std::decay_t<decltype(RenderSettings{}.*member)>;
            if constexpr (std::is_enum_v<T>) return choice_names(T{});
            else return {};
        },
        member);
}

std::string Setting::requirement() const {
    const SettingType t = type();
    if (t == SettingType::boolean) return "must be true or false";
    if (t == SettingType::enumeration || t == SettingType::set) {
        std::string names;
        for (const std::string& c : choices()) names += (names.empty() ? "" : ", ") + c;
        return (t == SettingType::set ? "must be some of: " : "must be one of: ") + names;
    }
    const bool real = t == SettingType::float_ || t == SettingType::double_;
    std::string text;
    const std::optional<SettingBound>&lo = min, &hi = max;
    if (!lo && !hi && !real)
        text = t == SettingType::uint ? "must be an integer >= 0" : "must be an integer";
    else if (lo && hi)
        text = std::string("must be in ") + (lo->open ? "(" : "[") + number(lo->value) + ", " + number(hi->value) +
               (hi->open ? ")" : "]");
    else if (lo)
        text = std::string("must be ") + (real ? "finite and " : "") + (lo->open ? "> " : ">= ") + number(lo->value);
    else if (hi && t == SettingType::uint)
        text = "must be in [0, " + number(hi->value) + (hi->open ? ")" : "]");
    else if (hi)
        text = std::string("must be ") + (real ? "finite and " : "") + (hi->open ? "below " : "at most ") +
               number(hi->value);
    else
        text = "must be finite";  // a real number without bounds
    if (unit == SettingUnit::degrees || unit == SettingUnit::seconds) text += std::string(" ") + to_string(unit);
    if (*note) text += std::string(" (") + note + ")";
    return text;
}

SettingValue Setting::get(const RenderSettings& settings) const {
    return std::visit(
        [&](auto m) -> SettingValue {
            using T = std::decay_t<decltype(settings.*m)>;
            const T value = settings.*m;
            if constexpr (std::is_same_v<T, bool>) return value;
            else if constexpr (std::is_same_v<T, FilmOutputSet>) return film_output_names(value);
            else if constexpr (std::is_enum_v<T>) return std::string(to_string(value));
            else if constexpr (std::is_floating_point_v<T>) return static_cast<double>(value);
            else if constexpr (std::is_unsigned_v<T>) return static_cast<uint64_t>(value);
            else return static_cast<int64_t>(value);
        },
        member);
}

void Setting::set(RenderSettings& settings, const SettingValue& value) const {
    const auto refuse = [&](const std::string& why) { throw InvalidInput(name, why + ", got " + describe(value)); };
    std::visit(
        [&](auto m) {
            using T = std::decay_t<decltype(settings.*m)>;
            if constexpr (std::is_same_v<T, bool>) {
                if (!std::holds_alternative<bool>(value)) refuse(requirement());
                settings.*m = std::get<bool>(value);
            } else if constexpr (std::is_same_v<T, FilmOutputSet>) {
                const auto* names = std::get_if<std::vector<std::string>>(&value);
                if (!names) refuse(requirement());
                settings.*m = film_output_set(*names);  // an unknown name is refused naming the known ones
            } else if constexpr (std::is_enum_v<T>) {
                if (!std::holds_alternative<std::string>(value)) refuse(requirement());
                for (const std::string& choice : choice_names(T{}))
                    if (choice == std::get<std::string>(value)) {
                        settings.*m = from_choice(T{}, choice);
                        return;
                    }
                refuse(requirement());
            } else if constexpr (std::is_floating_point_v<T>) {
                if (const double* d = std::get_if<double>(&value)) settings.*m = static_cast<T>(*d);
                else if (const int64_t* i = std::get_if<int64_t>(&value)) settings.*m = static_cast<T>(*i);
                else if (const uint64_t* u = std::get_if<uint64_t>(&value)) settings.*m = static_cast<T>(*u);
                else refuse(std::string("must be a number, not ") + kind_of(value));
            } else {  // integers: refused unless the member can hold the value exactly
                bool fits = false;
                if (const int64_t* i = std::get_if<int64_t>(&value)) {
                    fits = *i >= static_cast<int64_t>(std::numeric_limits<T>::min()) &&
                           (*i < 0 || static_cast<uint64_t>(*i) <= static_cast<uint64_t>(std::numeric_limits<T>::max()));
                    if (fits) settings.*m = static_cast<T>(*i);
                } else if (const uint64_t* u = std::get_if<uint64_t>(&value)) {
                    fits = *u <= static_cast<uint64_t>(std::numeric_limits<T>::max());
                    if (fits) settings.*m = static_cast<T>(*u);
                } else {
                    refuse(std::string("must be an integer, not ") + kind_of(value));
                }
                if (!fits) refuse(requirement());
            }
        },
        member);
}

void Setting::validate(const RenderSettings& settings) const {
    const SettingType t = type();
    // Every value such a member holds is valid (a set's bits beyond the outputs cannot be set from names).
    if (t == SettingType::boolean || t == SettingType::enumeration || t == SettingType::set) return;
    const SettingValue value = get(settings);
    const double v = std::visit(
        [](const auto& x) -> double {
            if constexpr (std::is_arithmetic_v<std::decay_t<decltype(x)>>) return static_cast<double>(x);
            else return 0.0;
        },
        value);
    const bool real = t == SettingType::float_ || t == SettingType::double_;
    bool ok = !real || std::isfinite(v);
    if (min) ok = ok && (min->open ? v > min->value : v >= min->value);
    if (max) ok = ok && (max->open ? v < max->value : v <= max->value);
    if (!ok) throw InvalidInput(name, requirement() + ", got " + describe(value));
}

void validate(const RenderSettings& s) {
    for (const Setting& row : render_settings_table()) row.validate(s);
    if (s.iterations == 0 && !(s.time_limit > 0.0))
        throw InvalidInput("iterations",
                           "0 (no iteration limit) needs a time_limit > 0, else the render would never end, got 0");
}

FilmOutputSet requested_outputs(const RenderSettings& settings) {
    FilmOutputSet outputs = (settings.outputs & kAllFilmOutputs) | film_bit(FilmOutput::combined);
    if (settings.caustics_pass) outputs |= film_bit(FilmOutput::caustics);
    return outputs;
}

}  // namespace ps
