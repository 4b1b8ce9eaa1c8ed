// View samples at glass: a camera path splits once, at its first glass surface, into a refracted and a reflected
// branch weighted by Fresnel (view_samples.h). The split must keep every pixel's expected radiance and remove
// the noise of choosing one branch at random.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "photonsplat/direct_light.h"
#include "photonsplat/render_control.h"
#include "photonsplat/stats.h"
#include "photonsplat/view_samples.h"
#include "test_scenes.h"

namespace {

using namespace ps;

constexpr int kSize = 48;

ViewSamples samples_of(const Scene& scene, uint64_t seed, bool split) {
    ViewSampleSettings settings;
    settings.seed = seed;
    settings.split_at_glass = split;
    RenderControl control;
    Stats stats;
    return generate_view_samples(scene, test::cornell_camera(kSize, kSize), settings, control, stats);
}

TEST(ViewSamples, GlassSplitsCameraPathsIntoFresnelWeightedBranches) {
    Scene scene;
    test::build_cornell_box(scene, true);
    const ViewSamples split = samples_of(scene, 3, true);
    const ViewSamples single = samples_of(scene, 3, false);
    ASSERT_GT(split.samples.size(), single.samples.size());

    std::vector<int> per_pixel(size_t(kSize) * kSize, 0);
    size_t split_pixels = 0, weights_sum_to_one = 0;
    for (size_t i = 0; i < split.samples.size(); ++i) {
        const ViewSample& s = split.samples[i];
        if (i > 0) ASSERT_LE(split.samples[i - 1].pixel, s.pixel) << "samples leave pixel order";
        ASSERT_LT(s.pixel, per_pixel.size());
        ++per_pixel[s.pixel];
        ASSERT_LE(per_pixel[s.pixel], 2) << "pixel " << s.pixel;
        // A second sample of a pixel is always its reflected branch (the refracted one comes first, when its
        // path did not escape or end); both came off glass.
        const bool second = per_pixel[s.pixel] == 2;
        if (second) EXPECT_NE(branch_of(s.flags), 0u) << "pixel " << s.pixel;
        if (branch_of(s.flags) != 0) EXPECT_TRUE(s.flags & kViaSpecular) << "pixel " << s.pixel;
        if (!second) continue;
        ++split_pixels;
        const ViewSample& refracted = split.samples[i - 1];
        EXPECT_EQ(branch_of(refracted.flags), 0u) << "pixel " << s.pixel;
        EXPECT_TRUE(refracted.flags & kViaSpecular);
        EXPECT_EQ(refracted.depth, s.depth) << "both branches key their clusters by the pixel's first hit";
        // Clear glass: F + (1 − F) = 1 where neither branch met the tinted mirror afterwards; never more.
        for (int c = 0; c < 3; ++c) {
            EXPECT_GT(s.throughput[c], 0.0f);
            EXPECT_LT(s.throughput[c], 1.0f);
            EXPECT_LE(s.throughput[c] + refracted.throughput[c], 1.0f + 1e-5f);
        }
        if (std::fabs(s.throughput.x + refracted.throughput.x - 1.0f) < 1e-5f) ++weights_sum_to_one;
    }
    // The glass sphere covers a few percent of this view; most of its pixels split.
    EXPECT_GT(split_pixels, size_t(kSize * kSize / 50));
    EXPECT_GT(weights_sum_to_one, split_pixels / 2);

    // Without the split: one sample a pixel at most, as before.
    std::vector<int> single_count(per_pixel.size(), 0);
    for (const ViewSample& s : single.samples) {
        EXPECT_EQ(branch_of(s.flags), 0u);
        EXPECT_LE(++single_count[s.pixel], 1);
    }
}

TEST(ViewSamples, SplitAtGlassKeepsTheMeanAndRemovesTheBranchNoise) {
    // Direct light seen through and in the glass sphere, per pixel over many seeds: both ways have the same
    // expectation; the split one does not vary with the branch choice.
    Scene scene;
    test::build_cornell_box(scene, true);
    constexpr int kSeeds = 48;
    const size_t pixels = size_t(kSize) * kSize;
    std::vector<double> sum[2], sum2[2];
    std::vector<uint8_t> via_glass(pixels, 0);
    for (int mode = 0; mode < 2; ++mode) {
        sum[mode].assign(pixels, 0.0);
        sum2[mode].assign(pixels, 0.0);
        for (int seed = 0; seed < kSeeds; ++seed) {
            const ViewSamples vs = samples_of(scene, uint64_t(seed), mode == 1);
            RenderControl control;
            Stats stats;
            DirectLightSettings light;
            light.seed = uint64_t(seed);
            const std::vector<glm::vec3> direct = compute_direct_light(scene, vs, light, control, stats);
            std::vector<double> image(pixels, 0.0);
            for (size_t i = 0; i < vs.samples.size(); ++i) {
                image[vs.samples[i].pixel] += direct[i].x + direct[i].y + direct[i].z;
                if (branch_of(vs.samples[i].flags) != 0) via_glass[vs.samples[i].pixel] = 1;
            }
            for (size_t p = 0; p < pixels; ++p) {
                sum[mode][p] += image[p];
                sum2[mode][p] += image[p] * image[p];
            }
        }
    }
    double mean[2] = {0, 0}, variance[2] = {0, 0};
    size_t count = 0;
    for (size_t p = 0; p < pixels; ++p) {
        if (!via_glass[p]) continue;
        ++count;
        for (int mode = 0; mode < 2; ++mode) {
            const double m = sum[mode][p] / kSeeds;
            mean[mode] += m;
            variance[mode] += sum2[mode][p] / kSeeds - m * m;
        }
    }
    ASSERT_GT(count, 30u);
    // Means over the glass pixels: the unsplit estimate's own noise is the tolerance's scale (a few percent).
    EXPECT_NEAR(mean[1] / mean[0], 1.0, 0.05) << "split " << mean[1] << " single " << mean[0];
    EXPECT_LT(variance[1], 0.5 * variance[0]) << "split " << variance[1] << " single " << variance[0];
}

}  // namespace
