#include "photonsplat/stats.h"

namespace ps {

void Stats::merge(const Stats& other) {
    for (const auto& [k, v] : other.seconds) seconds[k] += v;
    for (const auto& [k, v] : other.counters) counters[k] += v;
    for (const auto& [k, v] : other.bytes) bytes[k] = v;
    for (const auto& [k, v] : other.values) values[k] = v;
    for (const auto& [k, v] : other.predicted_bytes) predicted_bytes[k] = v;
}

}  // namespace ps
