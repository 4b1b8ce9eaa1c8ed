// Typed errors of the native core. Every message names the offending object or field and its value,
// so that the bindings can hand it to Python unchanged and the add-on can show it in Blender's UI.
#pragma once
#include <stdexcept>
#include <string>

namespace ps {

// Input that the core refuses: wrong sizes, NaN, out-of-range ids, negative counts...
// `field` is the name a script author would recognise ("radius", "mesh 'Cube'.vertices").
class InvalidInput : public std::invalid_argument {
public:
    InvalidInput(const std::string& field, const std::string& what)
        : std::invalid_argument(field + ": " + what), field_(field) {}
    const std::string& field() const { return field_; }

private:
    std::string field_;
};

// Thrown out of a render when its RenderControl was asked to cancel.
class Cancelled : public std::runtime_error {
public:
    Cancelled() : std::runtime_error("render cancelled") {}
};

}  // namespace ps
