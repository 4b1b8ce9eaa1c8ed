// Lookup by name in the core's tables of named rows (splat methods, film outputs): one place that turns a name
// from Python or Blender into its row, and an unknown name into a message listing the known ones.
#pragma once
#include <string>

#include "photonsplat/errors.h"

namespace ps {

// The row of `rows` (each with a `name`) called `name`; InvalidInput naming `field` when none is.
template <typename Rows>
const auto& row_named(const Rows& rows, const std::string& name, const std::string& field) {
    std::string known;
    for (const auto& row : rows) {
        if (name == row.name) return row;
        known += (known.empty() ? "" : ", ") + std::string(row.name);
    }
    throw InvalidInput(field, "'" + name + "' is not one of: " + known);
}

}  // namespace ps
