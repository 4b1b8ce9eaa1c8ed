// The settings of a render, and the table that describes each of them once: its name, type, default, valid range,
// the wording of its validation message, a line for user interfaces and its deprecated names. validate(), the
// Python bindings (RenderSettings keywords, properties, __repr__, photonsplat.SETTINGS) and the Blender
// properties are all generated from the table.
//
// Adding a setting: a member of RenderSettings (its initializer is the default) and one row in
// render_settings_table() (settings.cpp). A member of a type SettingMember does not list yet (a new enumeration)
// also needs an alternative there and, in settings.cpp, its choice names (choice_names, from_choice).
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "photonsplat/film.h"
#include "photonsplat/splat.h"

namespace ps {

struct RenderSettings {
    uint64_t photons = 200000;        // photon paths emitted
    float radius = 0.0f;              // kernel radius in world units; 0 = derived from the scene's size
    SplatMethod method = SplatMethod::cluster_cone;
    int max_bounces = 8;              // photon path length bound, and camera-path specular depth bound
    uint64_t seed = 0;
    int threads = 0;                  // 0 = all cores
    int direct_samples = 4;           // shadow rays per light per view sample (soft shadows)
    float normal_tolerance = 60.0f;   // τ in degrees: photons on surfaces turned further away are ignored
    float plane_distance = 0.0f;      // κ of the plane-distance test (stacked surfaces); 0 = off
    Kernel kernel = Kernel::uniform;  // density-estimation kernel
    // Divide each view sample's splatted light by the part of its kernel disc that lies on a like-facing surface
    // (kernel_coverage.h): removes the darkening of corners, edges and thin parts (boundary bias). Every method
    // but directional, whose blocks are not kernel discs (it is corrected where it falls back to exact).
    bool boundary_correction = true;
    // Photons where they gather many times more densely than usual (focused caustics) splat with a half or a
    // quarter of the radius, so that their discs hold about as many photons as usual (photon_density.h).
    bool adaptive_radius = true;
    int directional_level = -1;       // directional method: hierarchy level from the leaves; -1 = from the radius
    uint64_t memory_budget = 0;       // bytes the render may hold; 0 = 3/4 of available memory (memory_budget.h)
    bool guide_photons = true;        // emit sun photons where pilot paths found them stored (emission_guide.h)
    // Extra photons per iteration aimed at mirror and glass objects from point, spot and area lights, as a fraction
    // of `photons`; they only add caustic photons (caustic_aim.h). 0 = off; nothing is added without mirrors
    // or glass.
    float aimed_photons = 0.1f;
    // The film outputs the render produces (film.h; combined always). Fewer outputs hold less memory, above all in
    // a progressive render's running sums.
    FilmOutputSet outputs = kDefaultFilmOutputs;
    bool caustics_pass = false;       // also produce the caustics output: the light Cycles' Caustics toggles remove
                                      // (photons.h: each photon's share of it, splatted alone)
    bool transparent = false;         // film transparency: alpha 0 and no background where camera rays escape
    // Progressive rendering (progressive.h): iterations of new photons, jittered camera rays and a shrinking radius,
    // averaged. 1 = the paper's one-shot method, exactly the image of a single iteration.
    uint32_t iterations = 1;          // 0 = no iteration limit (then time_limit must be > 0)
    double time_limit = 0.0;          // seconds of rendering; 0 = none. An iteration predicted to end past it is not started
    float alpha = 2.0f / 3.0f;        // Knaus & Zwicker: r_i² = r_{i−1}²·(i−1+α)/i; in (0, 1], 1 = fixed radius
};

// --- the settings table ---------------------------------------------------------------------------------------

// The member a row describes. Its type gives the setting's type: unsigned and signed integers, float, double,
// bool, or an enumeration (named by strings outside the core).
using SettingMember = std::variant<uint64_t RenderSettings::*, uint32_t RenderSettings::*, int RenderSettings::*,
                                   float RenderSettings::*, double RenderSettings::*, bool RenderSettings::*,
                                   SplatMethod RenderSettings::*, Kernel RenderSettings::*,
                                   FilmOutputSet RenderSettings::*>;

// `set`: any subset of the choices (the film's outputs), given as their names.
enum class SettingType { uint, int_, float_, double_, boolean, enumeration, set };
const char* to_string(SettingType type);  // "uint", "int", "float", "double", "bool", "enum", "set"

// What a value measures, for user interfaces (widgets, units); degrees and seconds are also said in messages.
enum class SettingUnit { none, length, degrees, seconds, bytes };
const char* to_string(SettingUnit unit);  // "", "length", "degrees", "seconds", "bytes"

// A bound of the valid range; `open` excludes the value itself.
struct SettingBound {
    double value = 0.0;
    bool open = false;
};

// A setting's value outside the struct: bool, a signed or unsigned integer, a real number, a choice's name or
// the names of a set's members.
using SettingValue = std::variant<bool, int64_t, uint64_t, double, std::string, std::vector<std::string>>;

struct Setting {
    const char* name;
    SettingMember member;
    std::optional<SettingBound> min;  // none: the type's own (0 for unsigned integers); reals must be finite
    std::optional<SettingBound> max;
    SettingUnit unit;
    const char* note;         // what special values mean, in the message's parentheses ("0 = automatic"); or ""
    const char* description;  // one line for user interfaces
    std::vector<std::string> aliases = {};  // deprecated names, still accepted by the Python bindings

    SettingType type() const;
    std::vector<std::string> choices() const;       // an enumeration's or a set's names, in order; else none
    std::string requirement() const;                // the message's wording: "must be in [1, 4096]"
    SettingValue get(const RenderSettings& settings) const;
    SettingValue default_value() const { return get(RenderSettings{}); }
    // Stores `value` converted to the member's type; throws InvalidInput naming the setting when it is of another
    // kind, is not representable (-1 for an unsigned count) or is not one of the choices. Does not check the range.
    void set(RenderSettings& settings, const SettingValue& value) const;
    // Throws InvalidInput naming the setting when its value in `settings` is outside the valid range.
    void validate(const RenderSettings& settings) const;
};

// Every setting of RenderSettings, one row each, in the order of the struct.
const std::vector<Setting>& render_settings_table();
// The row named `name`, or whose deprecated aliases include it; nullptr when there is none.
const Setting* find_setting(const std::string& name);

// Every row's range, then the rules between settings. Throws InvalidInput naming the field.
void validate(const RenderSettings& settings);

// The outputs a render with these settings fills: settings.outputs, combined, and caustics with caustics_pass.
FilmOutputSet requested_outputs(const RenderSettings& settings);

}  // namespace ps
