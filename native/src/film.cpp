#include "photonsplat/film.h"

#include "photonsplat/named_rows.h"

namespace ps {

namespace {

constexpr float kNoDepth = 1e10f;  // Cycles' depth of the background

FilmOutputSet with_combined(FilmOutputSet outputs) {
    return (outputs & kAllFilmOutputs) | film_bit(FilmOutput::combined);
}

size_t pixel_count(int width, int height) { return static_cast<size_t>(width) * static_cast<size_t>(height); }

}  // namespace

const std::array<FilmOutputInfo, kFilmOutputCount>& film_outputs() {
    static const std::array<FilmOutputInfo, kFilmOutputCount> outputs = {{
        {FilmOutput::combined, "combined", 4, true, 0.0f},
        {FilmOutput::emission, "emission", 3, true, 0.0f},
        {FilmOutput::direct, "direct", 3, true, 0.0f},
        {FilmOutput::indirect, "indirect", 3, true, 0.0f},
        {FilmOutput::caustics, "caustics", 3, true, 0.0f},
        {FilmOutput::normal, "normal", 3, false, 0.0f},
        {FilmOutput::depth, "depth", 1, false, kNoDepth},
    }};
    return outputs;
}

const FilmOutputInfo& film_output_info(FilmOutput output) { return film_outputs()[static_cast<size_t>(output)]; }

FilmOutput film_output_from_string(const std::string& name) {
    return row_named(film_outputs(), name, "outputs").output;
}

std::vector<std::string> film_output_names(FilmOutputSet set) {
    std::vector<std::string> names;
    for (const FilmOutputInfo& info : film_outputs())
        if (contains(set, info.output)) names.emplace_back(info.name);
    return names;
}

FilmOutputSet film_output_set(const std::vector<std::string>& names) {
    FilmOutputSet set{};
    for (const std::string& name : names) set |= film_bit(film_output_from_string(name));
    return set;
}

Film::Film(int width, int height, FilmOutputSet outputs)
    : width_(width), height_(height), outputs_(with_combined(outputs)) {
    for (const FilmOutputInfo& info : film_outputs())
        if (has(info.output)) images_[index(info.output)].assign(pixel_count(width, height) * info.channels, info.empty);
}

size_t Film::bytes() const {
    size_t bytes = 0;
    for (const std::vector<float>& image : images_) bytes += image.size() * sizeof(float);
    return bytes;
}

FilmAccumulator::FilmAccumulator(int width, int height, FilmOutputSet outputs)
    : width_(width), height_(height), outputs_(with_combined(outputs)) {}

void FilmAccumulator::add(const Film& iteration) {
    const size_t pixels = pixel_count(width_, height_);
    for (const FilmOutputInfo& info : film_outputs()) {
        if (!contains(outputs_, info.output)) continue;
        const std::vector<float>& image = iteration[info.output];
        if (!info.averaged) {
            if (count_ == 0) first_[static_cast<size_t>(info.output)] = image;
            continue;
        }
        std::vector<double>& sum = sums_[static_cast<size_t>(info.output)];
        if (count_ == 0) sum.assign(pixels * info.channels, 0.0);
        for (size_t i = 0; i < sum.size(); ++i) sum[i] += static_cast<double>(image[i]);
    }
    ++count_;
}

std::vector<float> FilmAccumulator::mean(FilmOutput output) const {
    const FilmOutputInfo& info = film_output_info(output);
    if (count_ == 0 || !contains(outputs_, output)) return {};
    if (!info.averaged) return first_[static_cast<size_t>(output)];
    const std::vector<double>& sum = sums_[static_cast<size_t>(output)];
    std::vector<float> mean(sum.size());
    const double n = static_cast<double>(count_);
    for (size_t i = 0; i < sum.size(); ++i) mean[i] = static_cast<float>(sum[i] / n);
    return mean;
}

Film FilmAccumulator::mean() const {
    if (count_ == 0) return Film();
    Film film(width_, height_, outputs_);
    for (const FilmOutputInfo& info : film_outputs())
        if (film.has(info.output)) film[info.output] = mean(info.output);
    return film;
}

size_t FilmAccumulator::bytes() const {
    size_t bytes = 0;
    for (const std::vector<double>& sum : sums_) bytes += sum.size() * sizeof(double);
    for (const std::vector<float>& image : first_) bytes += image.size() * sizeof(float);
    return bytes;
}

double FilmAccumulator::bytes_per_pixel(FilmOutputSet outputs) {
    double bytes = 0.0;
    for (const FilmOutputInfo& info : film_outputs())
        if (contains(with_combined(outputs), info.output))
            bytes += info.channels * double(info.averaged ? sizeof(double) : sizeof(float));
    return bytes;
}

}  // namespace ps
