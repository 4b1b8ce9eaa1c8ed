// Progressive rendering: one pass is the one-shot image bit for bit, later passes follow the Knaus–Zwicker
// radius schedule with their own random streams, and bad progressive settings are refused by name.
// (Convergence, cancel, time limits and thread counts are tested from Python: tests/python/test_progressive.py.)
#include <cmath>

#include <gtest/gtest.h>

#include "photonsplat/errors.h"
#include "photonsplat/progressive.h"
#include "photonsplat/render.h"
#include "photonsplat/scene.h"
#include "test_scenes.h"

namespace {

using namespace ps;

const Scene& cornell() {
    static Scene* scene = [] {
        auto* s = new Scene;
        test::build_cornell_box(*s, true);
        return s;
    }();
    return *scene;
}

RenderSettings small_settings() {
    RenderSettings s;
    s.photons = 5000;
    s.seed = 3;
    s.method = SplatMethod::cluster_cone;
    return s;
}

TEST(Progressive, OnePassIsTheOneShotRenderBitForBit) {
    const Camera camera = test::cornell_camera(32, 24);
    RenderSettings settings = small_settings();
    RenderControl control;
    IterationParams pass0;
    pass0.radius = first_radius(cornell(), camera, settings);
    const RenderResult one_shot = render_iteration(cornell(), camera, settings, pass0, control);
    const RenderResult rendered = render(cornell(), camera, settings, control);  // passes = 1
    ProgressiveRender progressive(cornell(), camera, settings);
    progressive.run_iteration(control);
    const RenderResult mean = progressive.result();
    ASSERT_EQ(one_shot.rgba().size(), 32u * 24u * 4u);
    EXPECT_EQ(one_shot.rgba(), rendered.rgba());
    EXPECT_EQ(one_shot.rgba(), mean.rgba());
    EXPECT_EQ(one_shot.film[ps::FilmOutput::indirect], mean.film[ps::FilmOutput::indirect]);
    EXPECT_EQ(one_shot.film[ps::FilmOutput::direct], mean.film[ps::FilmOutput::direct]);
    EXPECT_EQ(mean.stats.values.at("iterations"), 1.0);
}

TEST(Progressive, RadiusShrinksAsKnausZwickerAndPassesDiffer) {
    const Camera camera = test::cornell_camera(16, 16);
    RenderSettings settings = small_settings();
    settings.radius = 0.2f;
    settings.iterations = 5;
    ProgressiveRender progressive(cornell(), camera, settings);
    RenderControl control;
    double r2 = 0.04;
    std::vector<float> previous;
    for (int i = 1; i <= 5; ++i) {
        EXPECT_NEAR(progressive.next_radius(), std::sqrt(r2), 1e-6) << "iteration " << i;
        EXPECT_FALSE(progressive.finished());
        progressive.run_iteration(control);
        EXPECT_NEAR(progressive.radius(), std::sqrt(r2), 1e-6);
        r2 *= (i + 2.0 / 3.0) / (i + 1.0);
        std::vector<float> image = progressive.image();
        if (!previous.empty()) EXPECT_NE(image, previous) << "iteration " << i << " added nothing new";
        previous = image;
    }
    EXPECT_TRUE(progressive.finished());
    EXPECT_EQ(progressive.iterations_done(), 5u);
    EXPECT_NE(iteration_seed(3, 1), iteration_seed(3, 2));
    EXPECT_EQ(iteration_seed(3, 0), 3u);
}

TEST(Progressive, BadSettingsAreRefusedByName) {
    const Camera camera = test::cornell_camera(8, 8);
    auto field_of = [&](RenderSettings s) -> std::string {
        try {
            ProgressiveRender p(cornell(), camera, s);
        } catch (const InvalidInput& e) {
            return e.field();
        }
        return "";
    };
    RenderSettings s = small_settings();
    s.iterations = 0;  // no pass limit and no time limit: would never end
    EXPECT_EQ(field_of(s), "iterations");
    s.time_limit = 1.0;
    EXPECT_EQ(field_of(s), "");
    s.time_limit = -1.0;
    EXPECT_EQ(field_of(s), "time_limit");
    s.time_limit = std::nan("");
    EXPECT_EQ(field_of(s), "time_limit");
    s = small_settings();
    for (float alpha : {0.0f, -0.5f, 1.5f, std::nanf("")}) {
        s.alpha = alpha;
        EXPECT_EQ(field_of(s), "alpha") << alpha;
    }
}

}  // namespace
