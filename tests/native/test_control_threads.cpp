// The render and whoever started it talk through RenderControl from different threads: progress read while the
// render writes it, a cancel requested while it runs. These tests are what the ThreadSanitizer step of
// scripts/sanitize.sh runs: the render uses one TBB thread (no hand-off inside the uninstrumented libtbb, which
// TSan cannot see), the caller is a std::thread, so every access TSan judges is one it can see synchronised.
#include <atomic>
#include <chrono>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "photonsplat/errors.h"
#include "photonsplat/render.h"
#include "photonsplat/scene.h"
#include "test_scenes.h"

namespace {

using namespace ps;

TEST(ControlAcrossThreads, ProgressIsReadWhileEveryMethodRenders) {
    Scene scene;
    test::build_cornell_box(scene, true);
    for (const std::string& name : splat_method_names()) {
        RenderSettings settings;
        settings.photons = 5000;
        settings.threads = 1;
        settings.method = splat_method_from_string(name);
        RenderControl control;
        std::atomic<bool> done{false};
        RenderResult result;
        std::thread worker([&] {
            result = render(scene, test::cornell_camera(24, 24), settings, control);
            done = true;
        });
        int polls = 0;
        while (!done) {
            std::string stage;
            double fraction = 0.0;
            control.progress(stage, fraction);
            EXPECT_GE(fraction, 0.0);
            EXPECT_LE(fraction, 1.0);
            ++polls;
            std::this_thread::yield();
        }
        worker.join();
        EXPECT_GT(polls, 0);
        EXPECT_EQ(result.rgba().size(), size_t(24 * 24 * 4)) << name;
    }
}

TEST(ControlAcrossThreads, CancelFromAnotherThreadEndsEveryMethod) {
    Scene scene;
    test::build_cornell_box(scene, true);
    for (const std::string& name : splat_method_names()) {
        RenderSettings settings;
        settings.photons = 2'000'000;  // far more than the test waits for
        settings.threads = 1;
        settings.method = splat_method_from_string(name);
        RenderControl control;
        std::atomic<bool> cancelled{false};
        std::thread worker([&] {
            try {
                render(scene, test::cornell_camera(48, 48), settings, control);
            } catch (const Cancelled&) {
                cancelled = true;
            }
        });
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        control.request_cancel();
        worker.join();
        EXPECT_TRUE(cancelled) << name;
    }
}

}  // namespace
