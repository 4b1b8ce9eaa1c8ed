// Stage 7's output: the film, the per-pixel images a render produces. Each output is a row of one table (as
// Cycles' passes): its name, its channels, how iterations of a progressive render combine it and its value where
// nothing was hit. Only the outputs a render asks for are allocated, filled, accumulated and returned; adding an
// output is one row here, its filling in render.cpp and its name in the add-on's passes.py.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ps {

enum class FilmOutput : uint8_t {
    combined,  // RGBA: emission + direct + indirect, alpha the film's coverage
    emission,  // light seen directly along camera paths: emitters and the world
    direct,    // shadow-ray light at the view samples
    indirect,  // splatted photons: light that bounced at least once
    caustics,  // the part of indirect carried by caustic photons (light, specular+, diffuse)
    normal,    // world-space normal of the first camera hit
    depth,     // distance along the camera axis of the first camera hit
};
constexpr size_t kFilmOutputCount = 7;

struct FilmOutputInfo {
    FilmOutput output;
    const char* name;  // the key of the Python API's pass dictionary
    int channels;
    // Progressive renders: true = the mean over iterations; false = the first iteration's (pixel-centred camera
    // rays), as Cycles keeps its first sample's normal and depth.
    bool averaged;
    float empty;  // the value of a pixel nothing was written to (Cycles' depth of the background for depth)
};
const std::array<FilmOutputInfo, kFilmOutputCount>& film_outputs();
const FilmOutputInfo& film_output_info(FilmOutput output);
FilmOutput film_output_from_string(const std::string& name);  // throws InvalidInput naming "outputs"

// A set of outputs, one bit per FilmOutput: a type of its own, so that the settings table tells it from a count.
enum class FilmOutputSet : uint32_t {};
constexpr FilmOutputSet operator|(FilmOutputSet a, FilmOutputSet b) { return FilmOutputSet(uint32_t(a) | uint32_t(b)); }
constexpr FilmOutputSet operator&(FilmOutputSet a, FilmOutputSet b) { return FilmOutputSet(uint32_t(a) & uint32_t(b)); }
constexpr FilmOutputSet operator~(FilmOutputSet a) { return FilmOutputSet(~uint32_t(a)); }
inline FilmOutputSet& operator|=(FilmOutputSet& a, FilmOutputSet b) { return a = a | b; }
constexpr FilmOutputSet film_bit(FilmOutput output) { return FilmOutputSet(uint32_t(1) << unsigned(output)); }
constexpr bool contains(FilmOutputSet set, FilmOutput output) { return uint32_t(set & film_bit(output)) != 0; }
constexpr FilmOutputSet kAllFilmOutputs = FilmOutputSet((uint32_t(1) << kFilmOutputCount) - 1);
// What a render produces unless told otherwise: every output but caustics, which costs a second splat.
constexpr FilmOutputSet kDefaultFilmOutputs = kAllFilmOutputs & ~film_bit(FilmOutput::caustics);
std::vector<std::string> film_output_names(FilmOutputSet set);  // in the table's order
FilmOutputSet film_output_set(const std::vector<std::string>& names);  // throws InvalidInput naming "outputs"

// The images of one render or iteration, row 0 at the top. Combined is always there.
class Film {
public:
    Film() = default;
    // Allocates every output in `outputs` (and combined), each pixel at its output's empty value.
    Film(int width, int height, FilmOutputSet outputs);

    int width() const { return width_; }
    int height() const { return height_; }
    FilmOutputSet outputs() const { return outputs_; }
    bool has(FilmOutput output) const { return contains(outputs_, output); }
    // The output's pixels, height × width × channels; empty when the film does not hold it.
    std::vector<float>& operator[](FilmOutput output) { return images_[index(output)]; }
    const std::vector<float>& operator[](FilmOutput output) const { return images_[index(output)]; }
    size_t bytes() const;

private:
    static size_t index(FilmOutput output) { return static_cast<size_t>(output); }
    int width_ = 0, height_ = 0;
    FilmOutputSet outputs_{};
    std::array<std::vector<float>, kFilmOutputCount> images_;
};

// The running sums of a progressive render: averaged outputs summed in double (after 10⁴ iterations a float sum
// would have lost 3–4 digits), the others kept from the first iteration.
class FilmAccumulator {
public:
    FilmAccumulator() = default;
    FilmAccumulator(int width, int height, FilmOutputSet outputs);

    void add(const Film& iteration);  // an iteration's film, holding at least this accumulator's outputs
    uint32_t count() const { return count_; }
    // The mean of what was added: every output, or only one (an empty film or image before the first add).
    Film mean() const;
    std::vector<float> mean(FilmOutput output) const;
    size_t bytes() const;
    // What the sums of these outputs hold per pixel.
    static double bytes_per_pixel(FilmOutputSet outputs);

private:
    int width_ = 0, height_ = 0;
    FilmOutputSet outputs_{};
    uint32_t count_ = 0;
    std::array<std::vector<double>, kFilmOutputCount> sums_;  // averaged outputs
    std::array<std::vector<float>, kFilmOutputCount> first_;  // the others
};

}  // namespace ps
