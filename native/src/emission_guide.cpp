#include "photonsplat/emission_guide.h"

#include <algorithm>
#include <cmath>

namespace ps {

EmissionGuide EmissionGuide::from_usefulness(const std::vector<double>& usefulness) {
    EmissionGuide guide;
    if (usefulness.size() != size_t(kCells)) return guide;
    double total = 0.0;
    for (double u : usefulness) {
        if (!(u >= 0.0) || !std::isfinite(u)) return guide;
        total += u;
    }
    if (!(total > 0.0) || !std::isfinite(total)) return guide;
    guide.pdf_.resize(kCells);
    guide.cdf_.resize(kCells);
    double running = 0.0;
    for (int c = 0; c < kCells; ++c) {
        const double p = (1.0 - kUniformShare) * usefulness[size_t(c)] / total + kUniformShare / kCells;
        guide.pdf_[size_t(c)] = float(p * kCells);
        running += p;
        guide.cdf_[size_t(c)] = float(running);
    }
    guide.cdf_.back() = 1.0f;
    return guide;
}

float EmissionGuide::sample(float u_cell, float& u1, float& u2) const {
    if (cdf_.empty()) return 1.0f;
    const size_t c = std::min(size_t(std::upper_bound(cdf_.begin(), cdf_.end(), u_cell) - cdf_.begin()),
                              size_t(kCells - 1));
    const int x = int(c) % kCellsPerAxis, y = int(c) / kCellsPerAxis;
    // Stay inside [0, 1): (x + u)/n can round up to the cell's far edge, which is the next cell's.
    u1 = std::min((float(x) + u1) / float(kCellsPerAxis), std::nextafter(1.0f, 0.0f));
    u2 = std::min((float(y) + u2) / float(kCellsPerAxis), std::nextafter(1.0f, 0.0f));
    return 1.0f / pdf_[c];
}

double EmissionGuide::pdf(int cell) const { return cdf_.empty() ? 1.0 : double(pdf_[size_t(cell)]); }

}  // namespace ps
