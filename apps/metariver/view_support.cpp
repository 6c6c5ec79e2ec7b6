// The viewer's parts outside its loop (view_support.h).
#include "view_support.h"

#include "driver.h"

#include <metariver/io.h>
#include <metariver/render.h>
#include <metariver/scene_keys.h>

// libepoxy's GL header first; GLFW must not pull in its own.
#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string_view>

namespace mr::app {

namespace fs = std::filesystem;

std::string Recording::start(const ExportDef& def, const Simulation& sim) {
    auto e = Exporter::begin(def);
    if (!e) return e.error().message;
    if (auto s = e.value()->write_terrain(sim.terrain()); !s) return s.error().message;
    exporter = std::move(e.value());
    next_frame = 0;
    return fmt::format("recording to {}", def.dir);
}

std::string Recording::step(const Simulation& sim, double dt) {
    const long long f = next_frame++;
    if (!exporter->due(f)) return {};
    if (auto s = write_export_frame(*exporter, f, double(f + 1) * dt, sim); !s) {
        exporter.reset();
        return s.error().message;
    }
    return {};
}

std::string Recording::stop() {
    if (!exporter) return {};
    std::string message = fmt::format("exported {} frames to {}", exporter->frames().size(), exporter->def().dir);
    if (auto s = exporter->finish(); !s) message = s.error().message;
    exporter.reset();
    return message;
}

void install_input_callbacks(GLFWwindow* window, Input& input) {
    glfwSetWindowUserPointer(window, &input);
    // Ours first: ImGui's GLFW backend chains to callbacks installed before it.
    glfwSetScrollCallback(window, [](GLFWwindow* w, double, double dy) {
        static_cast<Input*>(glfwGetWindowUserPointer(w))->scroll += static_cast<float>(dy);
    });
    glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int) {
        if (action == GLFW_PRESS) static_cast<Input*>(glfwGetWindowUserPointer(w))->keys.push_back(key);
    });
    glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int button, int action, int) {
        if (button != GLFW_MOUSE_BUTTON_LEFT) return;
        auto* in = static_cast<Input*>(glfwGetWindowUserPointer(w));
        double x = 0, y = 0;
        glfwGetCursorPos(w, &x, &y);
        if (action == GLFW_PRESS) {
            in->press_x = x;
            in->press_y = y;
            ++in->left_presses;
        } else if (action == GLFW_RELEASE && std::abs(x - in->press_x) + std::abs(y - in->press_y) <= 4.0) {
            in->clicks.push_back({x, y});
        }
    });
    glfwSetDropCallback(window, [](GLFWwindow* w, int count, const char** paths) {
        auto* in = static_cast<Input*>(glfwGetWindowUserPointer(w));
        for (int i = 0; i < count; ++i) in->dropped.emplace_back(paths[i]);
    });
}

std::vector<MarkerBox> scene_markers(const Simulation& sim) {
    const SceneDef& d = sim.def();
    const SpawnDef& sp = d.spawn;
    const auto source = [&](const Vec3& c, const Vec3& h, int number) {
        const Vec3 e = glm::max(source_half_size(sp.shape, h), Vec3(0.2f));
        return MarkerBox{.lo = c - e, .hi = c + e, .sink = false, .number = number};
    };
    std::vector<MarkerBox> out{source(sp.center, sp.half_extent, 0)};
    for (size_t k = 0; k < sp.sources.size(); ++k)
        out.push_back(source(sp.sources[k].center, sp.sources[k].half_extent, int(k) + 1));
    if (d.sink.kind == SinkKind::Box) out.push_back({.lo = d.sink.min, .hi = d.sink.max, .sink = true, .number = 0});
    for (size_t k = 0; k < d.sink.boxes.size(); ++k)
        out.push_back({.lo = d.sink.boxes[k].min, .hi = d.sink.boxes[k].max, .sink = true, .number = int(k) + 1});
    return out;
}

/// What decides whether a scene edit needs the terrain (and tree) rebuilt and uploaded.
std::string terrain_key(const SceneDef& d) {
    return fmt::format("{}|{}|{}|{}|{}|{}|{}|{}|{}|{}", to_string(d.source.kind), d.source.heightmap, d.source.width,
                       d.source.height, d.source.seed, d.terrain.area_scale, d.terrain.auto_area_scale, d.terrain.height_scale,
                       d.terrain.paper_row_orientation, d.collision.leaf_triangles);
}

namespace {
/// The first number (000, 001, ...) for which no file named by `names` (patterns with one
/// {:03}) exists in `dir`; none when every one up to 99999 is taken.
std::optional<int> free_number(const std::string& dir, std::initializer_list<std::string_view> names) {
    for (int i = 0; i < 100000; ++i) {
        bool taken = false;
        for (std::string_view n : names) {
            std::error_code ec;
            taken |= fs::exists(fs::path(dir) / fmt::format(fmt::runtime(n), i), ec);
        }
        if (!taken) return i;
    }
    return std::nullopt;
}
}  // namespace

Result<std::string> save_terrain_and_scene(const Simulation& sim, const SceneDef& def, const std::string& dir) {
    std::error_code ec;
    const auto i = free_number(dir, {"metariver_terrain_{:03}.png", "metariver_scene_{:03}.toml"});
    if (!i) return Error{fmt::format("{}: metariver_terrain_000.png to _99999.png are all taken; save elsewhere", dir)};
    const fs::path png = fs::path(dir) / fmt::format("metariver_terrain_{:03}.png", *i);
    const fs::path toml = fs::path(dir) / fmt::format("metariver_scene_{:03}.toml", *i);
    auto saved = write_terrain_heightmap(png.string(), sim.terrain(), def.terrain.paper_row_orientation);
    if (!saved) return saved.error();
    SceneDef next = def;
    next.source.kind = TerrainSource::File;
    next.source.heightmap = fs::absolute(png, ec).string();
    next.terrain.area_scale = saved->area_scale;
    next.terrain.auto_area_scale = false;
    next.terrain.height_scale = saved->metres_max - saved->metres_min;
    next.terrain.condition = TerrainCondition::None;
    if (auto w = write_file_atomic(toml.string(), scene_to_toml(next)); !w) {
        fs::remove(png, ec);
        fs::remove(saved->sidecar, ec);
        return w.error();
    }
    return fmt::format("saved {} (+ .json) and {}", png.string(), toml.string());
}

std::string next_screenshot_path(const std::string& dir) {
    if (const auto i = free_number(dir, {"metariver_screenshot_{:03}.png"}))
        return (fs::path(dir) / fmt::format("metariver_screenshot_{:03}.png", *i)).string();
    return (fs::path(dir) / "metariver_screenshot.png").string();
}

/// Reads the window's back buffer (scene and UI) and writes it as a PNG.
Status screenshot(const std::string& path, int width, int height) {
    std::vector<uint8_t> rgb(static_cast<size_t>(width) * height * 3);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
    const size_t row = static_cast<size_t>(width) * 3;
    for (int y = 0; y < height / 2; ++y)
        std::swap_ranges(rgb.begin() + static_cast<long>(y * row), rgb.begin() + static_cast<long>((y + 1) * row),
                         rgb.begin() + static_cast<long>((height - 1 - y) * row));
    return write_png(path, rgb, width, height, 3);
}

}  // namespace mr::app
