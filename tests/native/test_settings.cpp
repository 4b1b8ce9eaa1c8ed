// The settings table (settings.h): it covers every member of RenderSettings once, every default is valid, every
// value outside a row's range is refused naming the row, and the messages keep the wording scripts have seen.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "photonsplat/errors.h"
#include "photonsplat/settings.h"

namespace {

using namespace ps;

// Counts the members of an aggregate of scalars: the most initializers `T{...}` accepts.
struct AnyMember {
    template <typename T>
    operator T() const;
};

template <typename T, typename... A>
constexpr auto brace_constructible(int) -> decltype(T{std::declval<A>()...}, true) {
    return true;
}
template <typename T, typename...>
constexpr bool brace_constructible(...) {
    return false;
}

template <typename T, typename... A>
constexpr size_t member_count() {
    if constexpr (brace_constructible<T, A..., AnyMember>(0)) return member_count<T, A..., AnyMember>();
    else return sizeof...(A);
}

size_t offset_of(const Setting& row) {
    const RenderSettings s;
    return std::visit([&](auto m) { return size_t(reinterpret_cast<const char*>(&(s.*m)) - reinterpret_cast<const char*>(&s)); },
                      row.member);
}

std::string field_refusing(const RenderSettings& s) {
    try {
        validate(s);
    } catch (const InvalidInput& e) {
        return e.field();
    }
    return "";
}

TEST(Settings, TheTableCoversEveryMemberOnce) {
    const auto& table = render_settings_table();
    EXPECT_EQ(table.size(), member_count<RenderSettings>()) << "a member of RenderSettings has no row, or a row too many";
    std::set<size_t> offsets;
    std::set<std::string> names;
    for (const Setting& row : table) {
        EXPECT_TRUE(offsets.insert(offset_of(row)).second) << row.name << " describes a member another row does";
        EXPECT_TRUE(names.insert(row.name).second) << row.name;
        for (const std::string& alias : row.aliases) EXPECT_TRUE(names.insert(alias).second) << alias;
        EXPECT_NE(std::string(row.description), "") << row.name;
    }
}

TEST(Settings, EveryDefaultIsValid) {
    EXPECT_NO_THROW(validate(RenderSettings{}));
    for (const Setting& row : render_settings_table()) {
        RenderSettings s;
        EXPECT_NO_THROW(row.validate(s)) << row.name;
        row.set(s, row.default_value());  // a value read back stores the same
        EXPECT_EQ(row.get(s), row.get(RenderSettings{})) << row.name;
    }
}

TEST(Settings, ValuesOutsideTheRangeAreRefusedNamingTheField) {
    int checked = 0;
    for (const Setting& row : render_settings_table()) {
        const bool real = row.type() == SettingType::float_ || row.type() == SettingType::double_;
        std::vector<double> bad;
        if (row.min) bad.push_back(row.min->open ? row.min->value : row.min->value - 1.0);
        if (row.max) bad.push_back(row.max->open ? row.max->value : row.max->value + (real ? 0.5 : 1.0));
        if (real) bad.insert(bad.end(), {std::nan(""), INFINITY, -INFINITY});
        for (double value : bad) {
            RenderSettings s;
            try {
                if (real) row.set(s, value);
                else if (value < 0) row.set(s, static_cast<int64_t>(value));
                else row.set(s, static_cast<uint64_t>(value));
            } catch (const InvalidInput& e) {  // not representable by the member: refused already
                EXPECT_EQ(e.field(), row.name) << value;
                ++checked;
                continue;
            }
            EXPECT_EQ(field_refusing(s), row.name) << row.name << " = " << value;
            try {
                row.validate(s);
                ADD_FAILURE() << row.name << " = " << value << " passed";
            } catch (const InvalidInput& e) {
                EXPECT_NE(std::string(e.what()).find(row.requirement()), std::string::npos) << e.what();
            }
            ++checked;
        }
        // The bounds themselves are valid unless open.
        for (const auto& b : {row.min, row.max}) {
            if (!b || b->open) continue;
            RenderSettings s;
            if (real) row.set(s, b->value);
            else row.set(s, static_cast<int64_t>(b->value));
            if (row.name != std::string("iterations") || b->value != 0.0) EXPECT_NO_THROW(validate(s)) << row.name;
        }
    }
    EXPECT_GE(checked, 25);
}

TEST(Settings, ValuesOfAnotherKindOrChoiceAreRefusedNamingTheField) {
    RenderSettings s;
    const auto field_of = [&](const char* name, const SettingValue& value) -> std::string {
        try {
            find_setting(name)->set(s, value);
        } catch (const InvalidInput& e) {
            return e.field();
        }
        return "";
    };
    EXPECT_EQ(field_of("method", std::string("fastest")), "method");
    EXPECT_EQ(field_of("kernel", std::string("gaussian")), "kernel");
    EXPECT_EQ(field_of("photons", int64_t(-1)), "photons");
    EXPECT_EQ(field_of("threads", int64_t(1) << 40), "threads");
    EXPECT_EQ(field_of("iterations", uint64_t(1) << 33), "iterations");
    EXPECT_EQ(field_of("radius", std::string("big")), "radius");
    EXPECT_EQ(field_of("guide_photons", 1.0), "guide_photons");
    EXPECT_EQ(field_of("method", std::string("gather")), "");
    EXPECT_EQ(s.method, SplatMethod::gather);
}

TEST(Settings, EnumerationsOfferTheCoresNames) {
    EXPECT_EQ(find_setting("method")->choices(), splat_method_names());
    EXPECT_EQ(find_setting("kernel")->choices(), (std::vector<std::string>{"uniform", "epanechnikov"}));
    EXPECT_EQ(find_setting("method")->get(RenderSettings{}), SettingValue(std::string("cluster_cone")));
}

TEST(Settings, DeprecatedNamesFindTheirSetting) {
    ASSERT_NE(find_setting("passes"), nullptr);
    EXPECT_EQ(std::string(find_setting("passes")->name), "iterations");
    EXPECT_EQ(find_setting("no_such_setting"), nullptr);
}

TEST(Settings, MessagesKeepTheirWording) {
    const auto requirement = [](const char* name) { return find_setting(name)->requirement(); };
    EXPECT_EQ(requirement("photons"), "must be in [0, 500000000]");
    EXPECT_EQ(requirement("radius"), "must be finite and >= 0 (0 = automatic)");
    EXPECT_EQ(requirement("direct_samples"), "must be in [1, 4096]");
    EXPECT_EQ(requirement("normal_tolerance"), "must be in (0, 180] degrees");
    EXPECT_EQ(requirement("iterations"), "must be in [0, 1000000] (0 = until time_limit)");
    EXPECT_EQ(requirement("time_limit"), "must be in [0, 10000000] seconds (0 = none)");
    EXPECT_EQ(requirement("seed"), "must be an integer >= 0");
    RenderSettings s;
    s.radius = -0.5f;
    try {
        validate(s);
        ADD_FAILURE();
    } catch (const InvalidInput& e) {
        EXPECT_STREQ(e.what(), "radius: must be finite and >= 0 (0 = automatic), got -0.500000");
    }
}

TEST(Settings, NoIterationLimitNeedsATimeLimit) {
    RenderSettings s;
    s.iterations = 0;
    EXPECT_EQ(field_refusing(s), "iterations");
    s.time_limit = 1.0;
    EXPECT_EQ(field_refusing(s), "");
}

}  // namespace
