#include "arrays.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>

#include "photonsplat/errors.h"

namespace ps_py {

using namespace pybind11::literals;

std::string shape_of(const py::array& a) {
    std::ostringstream s;
    s << "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) s << (i ? ", " : "") << a.shape(i);
    s << (a.ndim() == 1 ? ",)" : ")");
    return s.str();
}

std::string dtype_of(const py::array& a) { return py::str(a.dtype()).cast<std::string>(); }

namespace {

// Any real floating or integer array converted to T: float32 for float_array, float64 where positions need it
// (float64 input is then not rounded).
template <typename T>
py::array_t<T, py::array::c_style> real_array(const py::object& obj, const std::string& field) {
    py::array a = py::array::ensure(obj);
    if (!a) throw ps::InvalidInput(field, "must be a numpy array (or convertible to one)");
    const char kind = a.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u')
        throw ps::InvalidInput(field, "must hold real numbers, got dtype " + dtype_of(a));
    return py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(a);
}

// A glm vector of 3 finite components, read in its own precision.
template <typename Vec>
Vec vector3(const py::object& obj, const std::string& field) {
    const auto a = real_array<typename Vec::value_type>(obj, field);
    if (a.size() != 3) throw ps::InvalidInput(field, "must have 3 components, got shape " + shape_of(a));
    const Vec v(a.data()[0], a.data()[1], a.data()[2]);
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
        throw ps::InvalidInput(field, "must be finite");
    return v;
}

// Row-major numpy (math convention: world = M @ [x, y, z, 1]) into a column-major glm matrix of its precision.
template <typename Mat>
Mat matrix4(const py::object& obj, const std::string& field) {
    const auto a = real_array<typename Mat::value_type>(obj, field);
    require_shape(a, {4, 4}, field, "(4, 4)");
    Mat m;
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) m[c][r] = a.at(r, c);
    return m;
}

}  // namespace

py::array_t<float, py::array::c_style> float_array(const py::object& obj, const std::string& field) {
    return real_array<float>(obj, field);
}

py::array_t<int32_t, py::array::c_style> index_array(const py::object& obj, const std::string& field) {
    py::array a = py::array::ensure(obj);
    if (!a) throw ps::InvalidInput(field, "must be a numpy array (or convertible to one)");
    const char kind = a.dtype().kind();
    if (kind != 'i' && kind != 'u') throw ps::InvalidInput(field, "must hold integers, got dtype " + dtype_of(a));
    if (a.itemsize() > 4 || (kind == 'u' && a.itemsize() == 4)) {
        // Wider integers: check the range before narrowing, so 2^32 + 1 does not silently become 1.
        py::array_t<int64_t, py::array::c_style | py::array::forcecast> wide =
            py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
        const int64_t* p = wide.data();
        for (py::ssize_t i = 0; i < wide.size(); ++i)
            if (p[i] < INT32_MIN || p[i] > INT32_MAX)
                throw ps::InvalidInput(field, "value " + std::to_string(p[i]) + " at flat index " + std::to_string(i) +
                                                  " is out of range");
    }
    return py::array_t<int32_t, py::array::c_style | py::array::forcecast>::ensure(a);
}

void require_shape(const py::array& a, std::initializer_list<py::ssize_t> shape, const std::string& field,
                   const std::string& expected) {
    bool ok = a.ndim() == static_cast<py::ssize_t>(shape.size());
    py::ssize_t i = 0;
    for (py::ssize_t s : shape) {
        if (ok && s >= 0 && a.shape(i) != s) ok = false;
        ++i;
    }
    if (!ok) throw ps::InvalidInput(field, "must have shape " + expected + ", got " + shape_of(a));
}

glm::vec3 vec3(const py::object& obj, const std::string& field) { return vector3<glm::vec3>(obj, field); }
glm::dvec3 dvec3(const py::object& obj, const std::string& field) { return vector3<glm::dvec3>(obj, field); }
glm::dmat4 dmat4(const py::object& obj, const std::string& field) { return matrix4<glm::dmat4>(obj, field); }
glm::mat4 mat4(const py::object& obj, const std::string& field) { return matrix4<glm::mat4>(obj, field); }

LightReader::LightReader(ps::LightKind kind, const std::string& name) {
    light.name = name;
    light.kind = kind;
}

std::string LightReader::field(const std::string& name) const {
    return std::string(ps::to_string(light.kind)) + " light '" + light.name + "'." + name;
}

glm::vec3 LightReader::vector(const py::object& obj, const std::string& name) const { return vec3(obj, field(name)); }

glm::dvec3 LightReader::position(const py::object& obj, const std::string& name) const {
    return dvec3(obj, field(name));
}

int positive_int(const py::object& obj, const std::string& field) {
    if (!py::isinstance<py::int_>(obj)) throw ps::InvalidInput(field, "must be an integer");
    const long long v = obj.cast<long long>();
    if (v < 1 || v > 65536) throw ps::InvalidInput(field, "must be in [1, 65536], got " + std::to_string(v));
    return static_cast<int>(v);
}

py::array_t<float> image_array(const std::vector<float>& data, int height, int width, int channels) {
    py::array_t<float> a({height, width, channels});
    std::copy(data.begin(), data.end(), a.mutable_data());
    return a;
}

py::dict to_dict(const std::map<std::string, double>& m) {
    py::dict d;
    for (const auto& [k, v] : m) d[py::str(k)] = v;
    return d;
}

py::dict stats_dict(const ps::Stats& stats) {
    return py::dict("seconds"_a = to_dict(stats.seconds), "counters"_a = to_dict(stats.counters),
                    "bytes"_a = to_dict(stats.bytes), "values"_a = to_dict(stats.values),
                    "predicted_bytes"_a = to_dict(stats.predicted_bytes));
}

py::dict pass_images(const ps::RenderResult& r) {
    py::dict images;
    for (const ps::FilmOutputInfo& info : ps::film_outputs())
        if (info.output != ps::FilmOutput::combined && r.film.has(info.output))
            images[info.name] = image_array(r.film[info.output], r.height(), r.width(), info.channels);
    return images;
}

}  // namespace ps_py
