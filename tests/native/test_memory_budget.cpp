// The memory budget: predictions bound what the stats measure, a small budget refuses before allocating with a
// message naming the structure, and a budget that only fits a smaller pair cap still renders the same image.
#include <string>

#include <gtest/gtest.h>

#include "photonsplat/errors.h"
#include "photonsplat/memory_budget.h"
#include "photonsplat/render.h"
#include "photonsplat/scene.h"
#include "test_scenes.h"

namespace {

using namespace ps;

// Structures bounded by a cap the budget chooses rather than predicted from the data: the prediction is the
// cap's bytes, which can be far above what a small frame uses.
bool capped(const std::string& name) {
    return name == "leaf_photon_lists" || name == "tile_photon_lists" || name == "gather_lists" ||
           name == "splat_sample_sums";
}

// Every structure the stats report was predicted, the prediction is at least the measured bytes, and, over the
// structures not bounded by a cap, the predicted total is within 3× of the measured total (the photon map's
// prediction is the Russian-roulette bound, ~3× what the open Cornell box stores; the hierarchy's assumes one leaf
// per pixel, ~10× the 8×8-pixel leaves it has).
TEST(MemoryBudget, PredictionsBoundTheMeasuredBytesForEveryMethod) {
    Scene scene;
    test::build_cornell_box(scene, true);
    for (const std::string& name : splat_method_names()) {
        SCOPED_TRACE(name);
        RenderSettings settings;
        settings.photons = 20000;
        settings.method = splat_method_from_string(name);
        RenderControl control;
        const RenderResult r = render(scene, test::cornell_camera(64, 64), settings, control);
        double predicted = 0.0, measured = 0.0;
        for (const auto& [structure, bytes] : r.stats.bytes) {
            const auto it = r.stats.predicted_bytes.find(structure);
            ASSERT_NE(it, r.stats.predicted_bytes.end()) << structure << " was allocated without a prediction";
            EXPECT_GE(it->second, bytes) << structure;
            if (capped(structure)) continue;
            predicted += it->second;
            measured += bytes;
        }
        EXPECT_LE(predicted, 3.0 * measured);
        EXPECT_GE(predicted, measured);
    }
}

TEST(MemoryBudget, SmallBudgetRefusesBeforeAllocatingNamingStructureOverrunAndSetting) {
    Scene scene;
    test::build_cornell_box(scene, true);
    RenderSettings settings;
    settings.memory_budget = 300000;  // 300 kB: Embree's buffers fit (47 kB), the 64×64 view samples (475 kB) do not
    RenderControl control;
    try {
        render(scene, test::cornell_camera(64, 64), settings, control);
        FAIL() << "rendered over budget";
    } catch (const InvalidInput& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.field(), "resolution") << what;
        for (const char* part : {"view_samples", "over the memory budget", "lower resolution", "memory_budget"})
            EXPECT_NE(what.find(part), std::string::npos) << part << " missing from: " << what;
    }
}

// A budget with room for the frame but not for the default 32 Mi pairs lowers the pair cap (more batches) and
// gives the same image.
TEST(MemoryBudget, TightBudgetLowersThePairCapAndKeepsTheImage) {
    Scene scene;
    test::build_cornell_box(scene, true);
    RenderSettings settings;
    settings.photons = 20000;
    settings.radius = 3.0f;  // every photon reaches every leaf: about 3 M pairs
    settings.method = SplatMethod::cluster;
    RenderControl control;
    const RenderResult roomy = render(scene, test::cornell_camera(48, 48), settings, control);
    settings.memory_budget = 16u << 20;  // 16 MiB: about a million pairs after the frame's structures
    const RenderResult tight = render(scene, test::cornell_camera(48, 48), settings, control);
    EXPECT_GT(tight.stats.counters.at("splat_batches"), roomy.stats.counters.at("splat_batches"));
    EXPECT_LE(tight.stats.bytes.at("leaf_photon_lists"), tight.stats.predicted_bytes.at("leaf_photon_lists"));
    ASSERT_EQ(roomy.film[ps::FilmOutput::indirect].size(), tight.film[ps::FilmOutput::indirect].size());
    for (size_t i = 0; i < roomy.film[ps::FilmOutput::indirect].size(); ++i)
        EXPECT_NEAR(roomy.film[ps::FilmOutput::indirect][i], tight.film[ps::FilmOutput::indirect][i], 1e-4f * std::fabs(roomy.film[ps::FilmOutput::indirect][i]) + 1e-7f);
}

TEST(MemoryBudget, DefaultIsThreeQuartersOfAvailableMemory) {
    const uint64_t available = available_memory_bytes();
    ASSERT_GT(available, 0u);
    EXPECT_EQ(default_memory_budget(), available / 4 * 3);
}

}  // namespace
