// Routes (analysis/load/route.h, reports/routes.h; docs/routes.md): the interpolation by hand, the
// frame times of each sampling, exact per-frame counts of a route around a cube, the report's
// series, bad route files refused with the place, and check naming the frame in its JUnit.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <tuple>

#include <nlohmann/json.hpp>

#include "analysis/load/level_views.h"
#include "analysis/load/load.h"
#include "analysis/load/route.h"
#include "analysis/pipeline.h"
#include "reports/report.h"
#include "reports/routes.h"
#include "tests/temp_dir_test.h"
#include "tests/test_util.h"

namespace fs = std::filesystem;

namespace va {
namespace {

using Json = nlohmann::ordered_json;

// A cube [-1, 1]^3, faces counter-clockwise seen from outside (12 triangles, one object).
RawMesh cubeMesh() {
    RawMesh m;
    for (int i = 0; i < 8; ++i) m.positions.push_back({i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0});
    // Quads (a, b, c, d) counter-clockwise from outside, split (a, b, c) (a, c, d).
    const uint32_t q[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
    for (const auto &f : q) m.indices.insert(m.indices.end(), {f[0], f[1], f[2], f[0], f[2], f[3]});
    m.facesRead = 12;
    return m;
}

std::string cubeObj() {
    std::ostringstream s;
    const RawMesh m = cubeMesh();
    for (const Vec3 &p : m.positions) s << "v " << p.x << " " << p.y << " " << p.z << "\n";
    for (size_t t = 0; t < m.indices.size(); t += 3)
        s << "f " << m.indices[t] + 1 << " " << m.indices[t + 1] + 1 << " " << m.indices[t + 2] + 1 << "\n";
    return s.str();
}

RouteKeyframe key(Vec3 eye, double yaw, double time, double pitch = 0) {
    RouteKeyframe k;
    k.eye = eye, k.yaw = yaw, k.pitch = pitch, k.time = time;
    return k;
}

TEST(Route, InterpolationPassesThroughKeyframesAsDocumented) {
    Route r;
    r.up = 'z';
    r.interpolation = RouteInterpolation::catmullRom;
    r.keyframes = {key({0, 0, 0}, 350, 0), key({1, 1, 0}, 10, 1), key({2, 0, 0}, 10, 2, 30)};
    // At a keyframe's time: exactly its eye.
    for (const RouteKeyframe &k : r.keyframes) EXPECT_EQ(routePoseAt(r, k.time).eye, k.eye);
    // Before the start and past the end: the ends.
    EXPECT_EQ(routePoseAt(r, -5).eye, (Vec3{0, 0, 0}));
    EXPECT_EQ(routePoseAt(r, 9).eye, (Vec3{2, 0, 0}));
    // Catmull-Rom at t = 0.5: tangents m0 = (1, 1, 0) (one-sided), m1 = (P2 - P0) / 2 = (1, 0, 0);
    // Hermite weights at u = 1/2: 1/2, 1/8, 1/2, -1/8 -> x = 1/8 + 1/2 - 1/8, y = 1/8 + 1/2.
    const RoutePose p = routePoseAt(r, 0.5);
    EXPECT_EQ(p.eye, (Vec3{0.5, 0.625, 0}));
    // Yaw turns the shorter way: 350 -> 10 passes 360, not 180.
    EXPECT_EQ(p.yaw, 360);
    // Pitch is linear: halfway from 0 to 30 at t = 1.5.
    EXPECT_EQ(routePoseAt(r, 1.5).pitch, 15);
    // Linear: the chord.
    r.interpolation = RouteInterpolation::linear;
    EXPECT_EQ(routePoseAt(r, 0.5).eye, (Vec3{0.5, 0.5, 0}));
    EXPECT_EQ(routePoseAt(r, 1.25).eye, (Vec3{1.25, 0.75, 0}));
    // Direction: yaw 90 about z from +x is +y; pitch 90 would be +z (cos and sin of the angles).
    const Vec3 d = routeDirection('z', 90, 0);
    EXPECT_NEAR(d.x, 0, 1e-15);
    EXPECT_EQ(d.y, 1);
    EXPECT_EQ(d.z, 0);
    // y up: yaw 0 looks along +z, 90 along +x (orbit:N's frame).
    EXPECT_EQ(routeDirection('y', 0, 0), (Vec3{0, 0, 1}));
}

TEST(Route, FrameTimesOfEachSampling) {
    Route r;
    r.keyframes = {key({0, 0, 0}, 0, 0), key({1, 0, 0}, 0, 0.1), key({3, 0, 0}, 0, 0.3)};
    r.sampling.kind = RouteSampling::Kind::keyframes;
    EXPECT_EQ(routeFrameTimes(r), (std::vector<double>{0, 0.1, 0.3}));
    r.sampling.kind = RouteSampling::Kind::count;
    r.sampling.count = 4;
    EXPECT_EQ(routeFrameTimes(r), (std::vector<double>{0, 0.3 / 3, 0.3 * 2 / 3, 0.3}));
    r.sampling.count = 1;
    EXPECT_EQ(routeFrameTimes(r), (std::vector<double>{0}));
    // Every 0.1 s over 0.3 s: 4 frames, although 0.3 / 0.1 rounds below 3 (the quotient's derived
    // bound); the last frame is the route's end exactly.
    r.sampling.kind = RouteSampling::Kind::every;
    r.sampling.every = 0.1;
    ASSERT_LT(0.3 / 0.1, 3.0);
    const std::vector<double> t = routeFrameTimes(r);
    ASSERT_EQ(t.size(), 4u);
    EXPECT_EQ(t[0], 0);
    EXPECT_EQ(t[3], 0.3);
    r.sampling.every = 0.25;
    EXPECT_EQ(routeFrameTimes(r), (std::vector<double>{0, 0.25}));
}

// A route around a cube with linear interpolation: at each frame the backface stage keeps exactly
// the triangles of the faces the eye is in front of (2 per face), the z-buffer draws them all, and
// a closed convex mesh has overdraw exactly 1.
TEST(Route, CubeRouteCountsAreExactPerFrame) {
    Scene s = testing_util::sceneOf({cubeMesh()});
    Route r;
    r.name = "cube";
    r.file = "cube.route.json";
    r.up = 'y';
    r.interpolation = RouteInterpolation::linear;
    r.keyframes = {key({5, 0, 0}, 0, 0), key({5, 0, 5}, 0, 2), key({5, 5, 5}, 0, 4)};
    // Each keyframe looks at the cube's centre.
    for (RouteKeyframe &k : r.keyframes) {
        const Vec3 d = Vec3{0, 0, 0} - k.eye;
        k.yaw = std::atan2(d.x, d.z) * 180 / kPi;  // y up: yaw from +z towards +x
        k.pitch = std::atan2(d.y, std::hypot(d.x, d.z)) * 180 / kPi;
    }
    r.camera.width = 64;
    r.camera.height = 36;
    r.camera.nearZ = 0.1;
    r.camera.farZ = 100;
    r.sampling.kind = RouteSampling::Kind::count;
    r.sampling.count = 5;
    const std::vector<ViewSpec> views = routeViews(r);
    ASSERT_EQ(views.size(), 5u);
    // Frames at t = 0..4: eyes (5,0,0) (5,0,2.5) (5,0,5) (5,2.5,5) (5,5,5), in front of 1, 2, 2, 3, 3 faces.
    const std::vector<Vec3> eyes = {{5, 0, 0}, {5, 0, 2.5}, {5, 0, 5}, {5, 2.5, 5}, {5, 5, 5}};
    for (size_t i = 0; i < 5; ++i) {
        EXPECT_EQ(views[i].name, "cube@" + std::to_string(i));
        EXPECT_EQ(views[i].camera.eye, eyes[i]) << i;
        EXPECT_EQ(views[i].route.time, double(i));
        EXPECT_EQ(views[i].route.frame, i);
    }
    AnalysisResult out;
    std::string err;
    ASSERT_TRUE(analyzeScene(s, views, PipelineSettings{}, nullptr, &out, &err)) << err;
    const std::vector<uint64_t> drawn = {2, 4, 4, 6, 6};
    for (size_t i = 0; i < 5; ++i) {
        EXPECT_EQ(out.views[i].backface.trianglesCulled, 12 - drawn[i]) << i;
        EXPECT_EQ(out.views[i].zbuffer.trianglesDrawn, drawn[i]) << i;
        EXPECT_EQ(out.views[i].zbuffer.overdraw, 1.0) << i;
    }
    // The report's series: the same numbers per frame, the worst frames in order.
    out.routes = {r};
    const Json j = reportJson(out);
    ASSERT_TRUE(j.contains("routes"));
    const Json &rt = j["routes"][0];
    EXPECT_EQ(rt["name"], "cube");
    EXPECT_EQ(rt["interpolation"], "linear");
    EXPECT_EQ(rt["sampling"], (Json{{"frames", 5}}));
    EXPECT_EQ(rt["series"]["triangles_drawn"], (Json{2, 4, 4, 6, 6}));
    EXPECT_EQ(rt["series"]["overdraw"], (Json{1.0, 1.0, 1.0, 1.0, 1.0}));
    EXPECT_EQ(rt["series"]["time"], (Json{0.0, 1.0, 2.0, 3.0, 4.0}));
    EXPECT_EQ(rt["series"]["view"], (Json{0, 1, 2, 3, 4}));
    EXPECT_EQ(rt["series"]["false_cull_pixels"], (Json{0, 0, 0, 0, 0}));
    // Worst frames by triangles drawn: frames 3 and 4 (6 each, frame order), then 1.
    ASSERT_EQ(rt["worst"]["triangles_drawn"].size(), 3u);
    EXPECT_EQ(rt["worst"]["triangles_drawn"][0]["frame"], 3);
    EXPECT_EQ(rt["worst"]["triangles_drawn"][1]["frame"], 4);
    EXPECT_EQ(rt["worst"]["triangles_drawn"][2]["frame"], 1);
    // No false culls anywhere: nothing to list.
    EXPECT_TRUE(rt["worst"]["false_cull_pixels"].empty());
    EXPECT_EQ(j["views"][2]["route"], (Json{{"name", "cube"}, {"frame", 2}, {"time", 2.0}}));
    // The plot has a panel per metric and marks the worst frames in red (the worst's colour).
    const Canvas plot = routePlot(rt);
    size_t red = 0;
    for (size_t p = 0; p < plot.rgb.size(); p += 3) red += plot.rgb[p] == 210 && plot.rgb[p + 1] == 40 && plot.rgb[p + 2] == 30;
    EXPECT_GT(red, 0u);
}

// route:spawns on a real map: its spawn points (not the intermissions), nearest first, at the run
// speed; refused on a scene that is not a map.
TEST(Route, SpawnsRouteWalksAMapsSpawnPoints) {
    std::string err;
    Route r;
    Scene cube = testing_util::sceneOf({cubeMesh()});
    cube.path = "cube.obj";
    EXPECT_FALSE(spawnRoute(cube, &r, &err));
    EXPECT_EQ(err, "'cube.obj' is not a Quake 3 map; route:spawns walks a map's spawn points (write a route file instead)");
    const std::string thor = std::string(VISAUDIT_TEST_DATA) + "/openarena/pak6-patch088.pk3";
    if (!fs::exists(thor)) GTEST_SKIP() << "real data not fetched (run scripts/fetch-data.sh)";
    Scene s;
    ASSERT_TRUE(loadScene(thor + ":maps/oa_thor.bsp", {}, &s, &err)) << err;
    ASSERT_TRUE(spawnRoute(s, &r, &err)) << err;
    // One keyframe per distinct place (a few of oa_thor's spawn points share one).
    std::set<std::tuple<double, double, double>> places;
    for (const ViewSpec &v : spawnViews(s))
        if (v.name.rfind("spawn", 0) == 0) places.insert({v.camera.eye.x, v.camera.eye.y, v.camera.eye.z});
    EXPECT_EQ(r.keyframes.size(), places.size());
    EXPECT_EQ(r.keyframes[0].eye, spawnViews(s)[0].camera.eye);
    EXPECT_EQ(r.speed, 320);
    EXPECT_EQ(r.interpolation, RouteInterpolation::linear);
    for (size_t k = 1; k < r.keyframes.size(); ++k) {
        EXPECT_GT(r.keyframes[k].time, r.keyframes[k - 1].time);
        EXPECT_NEAR(r.keyframes[k].time - r.keyframes[k - 1].time,
                    length(r.keyframes[k].eye - r.keyframes[k - 1].eye) / 320, 1e-9);
    }
    // Nearest neighbour: the second keyframe is the spawn point nearest to the first.
    double nearest = INFINITY;
    for (const ViewSpec &v : spawnViews(s))
        if (v.name.rfind("spawn", 0) == 0 && !(v.camera.eye == r.keyframes[0].eye))
            nearest = std::min(nearest, length(v.camera.eye - r.keyframes[0].eye));
    EXPECT_EQ(length(r.keyframes[1].eye - r.keyframes[0].eye), nearest);
}

class RouteFileTest : public testing_util::TempDirTest {
  protected:
    RouteFileTest() : TempDirTest("route") {}
    // The message loading `text` as a route file gives (empty: it loaded).
    std::string loadError(const std::string &text, char up = 'y') {
        const fs::path p = dir_ / "r.route.json";
        std::ofstream(p) << text;
        Scene s = testing_util::sceneOf({cubeMesh()});
        s.up = up;
        Route r;
        std::string err;
        return loadRouteFile(p.string(), s, &r, &err) ? std::string() : err;
    }
    std::string file() const { return (dir_ / "r.route.json").string(); }
};

// fuzz_route_json's finding, byte for byte (STYLE 14): a keyframe eye at x = 5.6e51 loaded, and a
// frame's target (eye + direction) rounded onto its eye, so the frame had no camera.
TEST_F(RouteFileTest, FuzzFindingEyeTooFarForADirection) {
    const std::string input =
        "{\n"
        "  \"format\": \"visaudit-route/1\",\n"
        "  \"name\": \"thor-lower-loop\",\n"
        "  \"interpolation\": \"linear\",\n"
        "  \"speed\": 320,\n"
        "  \"keyframes\": [\n"
        "    { \"eye\": [-409, -563, -14], \"yaw\": 0 },\n"
        "    { \"eye\": [1362, -563, -14], \"yaw\": 0 },\n"
        "    { \"eye\": [1462, -663, -14], \"yaw\": -90 },\n"
        "    { \"eye\": [1462, -926, -14], \"yaw\": -90 },\n"
        "    { \"eye\": [555555555555555555555555555555555555555555555555551362, -1026, -14], \"yaw\": 180 },\n"
        "    { \"eye\": [-409, -1026, -14], \"yaw\": 180 }\n"
        "  ]\n"
        "}\n";
    EXPECT_EQ(loadError(input, 'z'), file() + ":11:14: keyframes[4].eye: has a coordinate beyond +-67108864, where a "
                                             "frame's camera cannot resolve its view direction; move the route (and "
                                             "its scene) nearer the origin");
}

TEST_F(RouteFileTest, BadRouteFilesAreRefusedWithTheFileThePlaceAndAFix) {
    const std::string head = "{\"format\": \"visaudit-route/1\", ";
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"target\": [0, 0, 0]}]}"),
              file() + ":1:45: keyframes: a route needs at least 2 keyframes, got 1; add the point where the route ends");
    EXPECT_EQ(loadError(head + "\"keyframe\": []}"),
              file() + ":1:32: unknown key 'keyframe' at the top level; did you mean 'keyframes'? (known keys: format, "
                       "name, interpolation, speed, camera, keyframes)");
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0, \"roll\": 3}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:75: unknown key 'roll' in keyframes[0]; known keys: eye, target, yaw, pitch, time");
    // JSON has no NaN: the parser names the place.
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [NaN, 0, 5], \"yaw\": 0}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:55: JSON syntax error: syntax error while parsing value - invalid literal; last read: "
                       "'\"eye\": [N'");
    // A literal too large for a double: refused at its place.
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 1e999}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:72: JSON error: number overflow parsing '1e999' (the number does not fit a double)");
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0, \"time\": 2}, {\"eye\": [1, 0, 5], \"yaw\": 0, \"time\": 1}]}"),
              file() + ":1:124: keyframes[1].time: 1 is not after keyframes[0].time (2); times must increase");
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0, \"time\": 0}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:87: keyframes[1]: missing \"time\": give a time on every keyframe or on none (then they are "
                       "one second apart, or spaced by \"speed\")");
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"target\": [0, 0, 0], \"yaw\": 3}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:86: keyframes[0].yaw: give either \"target\" or \"yaw\" and \"pitch\", not both");
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5]}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:46: keyframes[0]: missing \"target\" (a point to look at) or \"yaw\" (degrees about the up "
                       "axis; \"pitch\" optional)");
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0, \"pitch\": 90}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:84: keyframes[0].pitch: must be between -90 and 90 degrees (exclusive): the elevation above "
                       "the horizon");
    // Below 90 but too close for the camera model (|forward x up| = cos(pitch) <= 1e-9): refused at
    // the keyframe, not later at a frame.
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0, \"pitch\": 89.99999999999}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:84: keyframes[0].pitch: looks too nearly along the up axis for a camera; tilt it less "
                       "(pitch 89.99999999999)");
    // Past kRouteMinTilt (1e-6, about 0.00006 degrees from vertical) too: a frame's eye rounding
    // must not bring its direction to the camera model's 1e-9.
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0, \"pitch\": 89.99995}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:84: keyframes[0].pitch: looks too nearly along the up axis for a camera; tilt it less "
                       "(pitch 89.99995)");
    EXPECT_TRUE(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0, \"pitch\": 89.9999}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}").empty());
    // An eye beyond 2^26 (kRouteMaxCoordinate): a frame there could not resolve its direction
    // (fuzz_route_json: eye x 5.6e51 loaded, and a frame's target rounded onto its eye).
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0}, {\"eye\": [5.6e51, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:84: keyframes[1].eye: has a coordinate beyond +-67108864, where a frame's camera cannot "
                       "resolve its view direction; move the route (and its scene) nearer the origin");
    EXPECT_TRUE(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0}, {\"eye\": [67108864, 0, -67108864], \"yaw\": 0}]}").empty());
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"target\": [0, 5, 5]}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:75: keyframes[0].target: looks straight along the up axis (y); no yaw follows from it: move "
                       "the target sideways");
    EXPECT_EQ(loadError(head + "\"keyframes\": [{\"eye\": [0, 0, 5], \"target\": [0, 0, 5]}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:75: keyframes[0].target: equals \"eye\"; the keyframe has no direction");
    EXPECT_EQ(loadError(head + "\"speed\": 2, \"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0}, {\"eye\": [0, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:96: keyframes[1].eye: is where keyframes[0] is: with \"speed\" the route would stand still; "
                       "give times instead");
    EXPECT_EQ(loadError("{\"format\": \"visaudit-route/2\", \"keyframes\": []}"),
              file() + ":1:12: format: unsupported format \"visaudit-route/2\"; this visaudit reads \"visaudit-route/1\"");
    EXPECT_EQ(loadError(head + "\"camera\": {\"near\": 0}, \"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"),
              file() + ":1:51: camera: \"near\" must be > 0 (perspective depth is undefined at the eye); try 0.1");
    // A good file: no message; frames from "speed" (length 1 at 2 units/s: 0.5 s).
    EXPECT_EQ(loadError(head + "\"speed\": 2, \"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0}, {\"eye\": [1, 0, 5], \"yaw\": 0}]}"), "");
}

// The command line: a bad route is exit 2 with the place and no report; a route's frames are
// views that check judges one by one, naming the frame in the console and the JUnit; shards of a
// route merge into the single run's series.
class RouteCliTest : public testing_util::TempDirTest {
  protected:
    RouteCliTest() : TempDirTest("route-cli") {}
    struct Run {
        int code = -1;
        std::string out, err;
    };
    Run run(const std::string &args) {
        const fs::path o = dir_ / "stdout.txt", e = dir_ / "stderr.txt";
        const int status = std::system((std::string(VISAUDIT_BINARY) + " " + args + " </dev/null >" + o.string() +
                                        " 2>" + e.string()).c_str());
        auto slurp = [](const fs::path &p) {
            std::ifstream f(p);
            std::stringstream s;
            s << f.rdbuf();
            return s.str();
        };
        return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(o), slurp(e)};
    }
    void writeCubeAndRoute() {
        std::ofstream(dir_ / "cube.obj") << cubeObj();
        std::ofstream(dir_ / "cube.route.json")
            << "{\"format\": \"visaudit-route/1\", \"name\": \"cube\", \"interpolation\": \"linear\",\n"
               " \"camera\": {\"width\": 64, \"height\": 36, \"near\": 0.1, \"far\": 100},\n"
               " \"keyframes\": [{\"eye\": [5, 0, 0], \"target\": [0, 0, 0], \"time\": 0},\n"
               "               {\"eye\": [5, 0, 5], \"target\": [0, 0, 0], \"time\": 2},\n"
               "               {\"eye\": [5, 5, 5], \"target\": [0, 0, 0], \"time\": 4}]}\n";
    }
};

TEST_F(RouteCliTest, BadRouteIsExitTwoWithThePlaceAndNoReport) {
    std::ofstream(dir_ / "short.route.json") << "{\"format\": \"visaudit-route/1\",\n \"keyframes\": [{\"eye\": [0, 0, 5], \"yaw\": 0}]}\n";
    const fs::path out = dir_ / "out";
    Run r = run("analyze --views route:" + (dir_ / "short.route.json").string() + " --out " + out.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: " + (dir_ / "short.route.json").string() +
                         ":2:15: keyframes: a route needs at least 2 keyframes, got 1; add the point where the route ends\n");
    EXPECT_FALSE(fs::exists(out));
    r = run("analyze --views route:" + (dir_ / "short.route.json").string() + ":0 --out " + out.string());
    EXPECT_EQ(r.code, 2);
    EXPECT_EQ(r.err, "visaudit: error: --views route:" + (dir_ / "short.route.json").string() +
                         ":0: N must be a whole number from 1 to 100000; use route:FILE (a frame per keyframe), "
                         "route:FILE:N (N frames) or route:FILE:Ts (a frame every T seconds), e.g. "
                         "route:walk.route.json:60\n");
    EXPECT_FALSE(fs::exists(out));
}

TEST_F(RouteCliTest, CheckJudgesEveryFrameAndTheJUnitNamesIt) {
    writeCubeAndRoute();
    std::ofstream(dir_ / "budget.json") << "{\"format\": \"visaudit-budget/1\", \"limits\": {\"zbuffer_triangles\": 4}}\n";
    const Run r = run("check " + (dir_ / "cube.obj").string() + " --views route:" + (dir_ / "cube.route.json").string() +
                      ":5 --budget " + (dir_ / "budget.json").string() + " --junit " + (dir_ / "junit.xml").string() +
                      " --out " + (dir_ / "out").string() + " --quiet --images none");
    EXPECT_EQ(r.code, 1) << r.err;
    // Frames 3 and 4 draw 6 triangles; 0..2 draw 2, 4, 4 (and false_culls, limit 0 by default, passes).
    EXPECT_NE(r.out.find("FAIL: zbuffer_triangles in view 'cube@3' is 6, allowed 4 (triangles the z-buffer drew (after "
                         "every culling stage)) (frame 3 of route 'cube' at 3 s)\n"),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("8 passed, 2 failed"), std::string::npos) << r.out;
    std::ifstream f(dir_ / "junit.xml");
    std::stringstream junit;
    junit << f.rdbuf();
    EXPECT_NE(junit.str().find("<testcase classname=\"" + (dir_ / "cube.obj").string() +
                               ".cube@4\" name=\"limit zbuffer_triangles, frame 4 of route &apos;cube&apos; at 4 s\">"),
              std::string::npos)
        << junit.str();
    EXPECT_NE(junit.str().find("name=\"limit zbuffer_triangles, frame 0 of route &apos;cube&apos; at 0 s\"/>"),
              std::string::npos);
}

TEST_F(RouteCliTest, ShardsOfARouteMergeIntoTheSingleRunsSeries) {
    writeCubeAndRoute();
    // Timings read 0 (render/stopwatch.h): the plots' ms panel is then the same in every run.
    ::setenv("VISAUDIT_FIXED_TIMINGS", "1", 1);
    const std::string common = (dir_ / "cube.obj").string() + " --views route:" + (dir_ / "cube.route.json").string() +
                               ":1s --quiet --no-ordering --images key";
    ASSERT_EQ(run("analyze " + common + " --out " + (dir_ / "single").string()).code, 0);
    ASSERT_EQ(run("analyze " + common + " --shard 1/2 --out " + (dir_ / "s1").string()).code, 0);
    ASSERT_EQ(run("analyze " + common + " --shard 2/2 --out " + (dir_ / "s2").string()).code, 0);
    const Run m = run("merge " + (dir_ / "s1").string() + " " + (dir_ / "s2").string() + " --out " +
                      (dir_ / "merged").string() + " --quiet");
    ASSERT_EQ(m.code, 0) << m.err;
    auto routes = [](const fs::path &p) {
        std::ifstream f(p / "report.json");
        Json j = Json::parse(f)["routes"];
        for (Json &r : j) {
            r["series"].erase("total_ms");
            r["worst"].erase("total_ms");
        }
        return j;
    };
    const Json single = routes(dir_ / "single");
    EXPECT_EQ(single[0]["series"]["triangles_drawn"], (Json{2, 4, 4, 6, 6}));
    EXPECT_EQ(routes(dir_ / "merged"), single);
    EXPECT_TRUE(fs::exists(dir_ / "merged" / "route-cube.png"));
    // The plot is the same image as the single run's.
    std::ifstream a(dir_ / "single" / "route-cube.png", std::ios::binary), b(dir_ / "merged" / "route-cube.png", std::ios::binary);
    std::stringstream sa, sb;
    sa << a.rdbuf();
    sb << b.rdbuf();
    EXPECT_TRUE(sa.str() == sb.str()) << "route-cube.png differs between the single run and the merge";
    ::unsetenv("VISAUDIT_FIXED_TIMINGS");
}

}  // namespace
}  // namespace va
