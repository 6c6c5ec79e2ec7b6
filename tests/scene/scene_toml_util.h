// Helpers of the scene-file tests: a TOML text parsed as dir/s.toml over the default scene,
// and an error that must name the file first, on one line, and contain a phrase.
#pragma once

#include <metariver/scene.h>

#include <gtest/gtest.h>

#include <string>

namespace mr::scene_test {

inline Result<SceneDef> parse(const std::string& text) { return parse_scene_toml(text, "dir/s.toml", default_scene()); }

inline void expect_error(const std::string& text, const std::string& must_contain) {
    auto r = parse(text);
    ASSERT_FALSE(r.ok()) << "accepted: " << text;
    EXPECT_NE(r.error().message.find(must_contain), std::string::npos)
        << "message '" << r.error().message << "' lacks '" << must_contain << "'";
    EXPECT_EQ(r.error().message.find('\n'), std::string::npos) << "one line";
    EXPECT_EQ(r.error().message.rfind("dir/s.toml", 0), 0u) << "names the file first";
}

}  // namespace mr::scene_test
