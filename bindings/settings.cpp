// RenderSettings for Python, generated from the core's settings table (settings.h): the keyword arguments, one
// property per setting (validated as it is set), the deprecated names, __repr__, and photonsplat.SETTINGS, the
// table as data from which the Blender add-on builds its properties.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "bindings.h"
#include "photonsplat/errors.h"
#include "photonsplat/settings.h"

namespace py = pybind11;

namespace ps_py {

namespace {

py::object to_python(const ps::SettingValue& value) {
    return std::visit(
        [](const auto& v) -> py::object {
            if constexpr (std::is_same_v<std::decay_t<decltype(v)>, std::vector<std::string>>)
                return py::tuple(py::cast(v));  // a set's names, as an immutable tuple
            else
                return py::cast(v);
        },
        value);
}

std::string type_name(const py::handle& value) { return py::str(py::type::of(value).attr("__name__")); }

// A Python value as the setting's type holds it. A value of another kind (a string for a count) is a TypeError;
// one of the right kind but out of reach of the member (-1 for a count) is the core's InvalidInput (ValueError).
ps::SettingValue from_python(const ps::Setting& row, const py::handle& value) {
    PyObject* const o = value.ptr();
    const auto wrong_kind = [&](const std::string& wanted) {
        return py::type_error(std::string(row.name) + ": must be " + wanted + ", got " + type_name(value));
    };
    const bool text = PyUnicode_Check(o) || PyBytes_Check(o);
    switch (row.type()) {
        case ps::SettingType::boolean: {
            if (text || !(PyBool_Check(o) || PyNumber_Check(o))) throw wrong_kind("True or False");
            const int truth = PyObject_IsTrue(o);
            if (truth < 0) throw py::error_already_set();
            return truth != 0;
        }
        case ps::SettingType::enumeration:
            if (!PyUnicode_Check(o)) throw wrong_kind("a string");
            return value.cast<std::string>();
        case ps::SettingType::set: {
            if (text || !PyIter_Check(py::iter(value).ptr())) throw wrong_kind("a list of names");
            std::vector<std::string> names;
            for (const py::handle item : value) {
                if (!PyUnicode_Check(item.ptr())) throw wrong_kind("a list of names");
                names.push_back(item.cast<std::string>());
            }
            return names;
        }
        case ps::SettingType::float_:
        case ps::SettingType::double_: {
            if (text || !PyNumber_Check(o)) throw wrong_kind("a number");
            const double d = PyFloat_AsDouble(o);
            if (d == -1.0 && PyErr_Occurred()) throw py::error_already_set();
            return d;
        }
        case ps::SettingType::uint:
        case ps::SettingType::int_: {
            if (text || !PyIndex_Check(o)) throw wrong_kind("an integer");
            const py::object index = py::reinterpret_steal<py::object>(PyNumber_Index(o));
            if (!index) throw py::error_already_set();
            int overflow = 0;
            const long long i = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
            if (i == -1 && PyErr_Occurred()) throw py::error_already_set();
            if (overflow == 0) return static_cast<int64_t>(i);
            if (overflow > 0) {
                const unsigned long long u = PyLong_AsUnsignedLongLong(index.ptr());
                if (!PyErr_Occurred()) return static_cast<uint64_t>(u);
                PyErr_Clear();
            }
            throw ps::InvalidInput(row.name, row.requirement() + ", got " + std::string(py::str(index)));
        }
    }
    throw wrong_kind("a setting's value");
}

void warn_deprecated(const std::string& old_name, const ps::Setting& row) {
    const std::string message = "RenderSettings." + old_name + " is deprecated, use " + row.name;
    if (PyErr_WarnEx(PyExc_DeprecationWarning, message.c_str(), 1) < 0) throw py::error_already_set();
}

ps::RenderSettings make_settings(const py::kwargs& kwargs) {
    ps::RenderSettings settings;
    std::set<const ps::Setting*> given;
    for (const auto& [key, value] : kwargs) {
        const std::string name = py::str(key);
        const ps::Setting* row = ps::find_setting(name);
        if (!row) throw py::type_error("RenderSettings() got an unexpected keyword argument '" + name + "'");
        if (!given.insert(row).second)
            throw py::type_error("RenderSettings() got '" + std::string(row->name) + "' twice (once by a deprecated name)");
        if (name != row->name) warn_deprecated(name, *row);
        row->set(settings, from_python(*row, value));
    }
    ps::validate(settings);
    return settings;
}

// Sets one setting and checks its range; the rules between settings are checked when a render starts.
void set_checked(const ps::Setting& row, ps::RenderSettings& settings, const py::handle& value) {
    ps::RenderSettings changed = settings;
    row.set(changed, from_python(row, value));
    row.validate(changed);
    settings = changed;
}

// A value as Python source; a float member with the fewest digits that give it back (0.1, not 0.100000001).
std::string source(const ps::Setting& row, const ps::SettingValue& value) {
    if (row.type() == ps::SettingType::float_) {
        const float f = static_cast<float>(std::get<double>(value));
        char text[32];
        for (int digits = 6; digits <= 9; ++digits) {
            std::snprintf(text, sizeof text, "%.*g", digits, static_cast<double>(f));
            if (std::strtof(text, nullptr) == f || digits == 9) return py::repr(py::float_(std::strtod(text, nullptr)));
        }
    }
    return py::repr(to_python(value));
}

std::string repr(const ps::RenderSettings& settings) {
    std::string text = "RenderSettings(";
    for (const ps::Setting& row : ps::render_settings_table()) {
        if (text.back() != '(') text += ", ";
        text += std::string(row.name) + "=" + source(row, row.get(settings));
    }
    return text + ")";
}

py::object bound(const ps::Setting& row, const std::optional<ps::SettingBound>& b, bool lower) {
    const bool integer = row.type() == ps::SettingType::uint || row.type() == ps::SettingType::int_;
    if (!b) return lower && row.type() == ps::SettingType::uint ? py::object(py::int_(0)) : py::object(py::none());
    if (integer) return py::int_(static_cast<long long>(b->value));
    return py::float_(b->value);
}

// photonsplat.SETTINGS: one dict per setting, in the order of the core's table.
py::tuple settings_description() {
    py::list rows;
    for (const ps::Setting& row : ps::render_settings_table()) {
        py::dict d;
        d["name"] = row.name;
        d["type"] = ps::to_string(row.type());
        d["default"] = to_python(row.default_value());
        d["min"] = bound(row, row.min, true);
        d["max"] = bound(row, row.max, false);
        d["min_exclusive"] = row.min && row.min->open;
        d["max_exclusive"] = row.max && row.max->open;
        d["choices"] = py::tuple(py::cast(row.choices()));
        d["unit"] = ps::to_string(row.unit);
        d["description"] = row.description;
        d["requirement"] = row.requirement();
        d["aliases"] = py::tuple(py::cast(row.aliases));
        rows.append(d);
    }
    return py::tuple(rows);
}

std::string init_doc() {
    std::string doc = "RenderSettings(**settings): any of the settings below by keyword, the others at their "
                      "default; validated on construction (ValueError naming the setting). Unknown keywords are a "
                      "TypeError; deprecated names still work and warn.\n";
    for (const ps::Setting& row : ps::render_settings_table()) {
        doc += std::string("\n") + row.name + " (" + ps::to_string(row.type()) +
               ", default " + std::string(py::repr(to_python(row.default_value()))) + "): " + row.description;
        for (const std::string& alias : row.aliases) doc += " [deprecated name: " + alias + "]";
    }
    return doc;
}

}  // namespace

void bind_settings(py::module_& m) {
    py::class_<ps::RenderSettings> settings(m, "RenderSettings",
                                            "Settings of one render; validated on construction and as each is set.");
    settings.def(py::init(&make_settings), init_doc().c_str());
    for (const ps::Setting& row : ps::render_settings_table()) {
        const ps::Setting* r = &row;
        const std::string doc = std::string(row.description) + ". Valid: " + row.requirement() + ".";
        settings.def_property(
            row.name, [r](const ps::RenderSettings& s) { return to_python(r->get(s)); },
            [r](ps::RenderSettings& s, const py::object& v) { set_checked(*r, s, v); }, doc.c_str());
        for (const std::string& alias : row.aliases)
            settings.def_property(
                alias.c_str(),
                [r, alias](const ps::RenderSettings& s) {
                    warn_deprecated(alias, *r);
                    return to_python(r->get(s));
                },
                [r, alias](ps::RenderSettings& s, const py::object& v) {
                    warn_deprecated(alias, *r);
                    set_checked(*r, s, v);
                },
                ("Deprecated name of " + std::string(row.name) + ".").c_str());
    }
    settings.def("__repr__", &repr);
    m.attr("SETTINGS") = settings_description();
}

}  // namespace ps_py
