// `shatter simulate` end to end: every scene runs and reports its breaks, output
// and recording are the same bytes on every run, a damaged .shatter is refused as
// `info` refuses it, usage mistakes exit 2, and --record is all or nothing.

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "runtime_cases.hpp"
#include "shatter/formats/file.hpp"
#include "support/run_shatter.hpp"

using namespace shatter;
using namespace shatter::test;
namespace fs = std::filesystem;

namespace {


// A .shatter file of `mesh` in the scratch folder (written by the library, so the
// test reads only what it made).
fs::path tree_file(const std::string& mesh, std::uint32_t fragments) {
  const fs::path path = scratch(mesh + "-" + std::to_string(fragments) + ".shatter");
  write_shatter_file(path, *runtime_case(mesh, fragments, 7).tree);
  return path;
}

}  // namespace

TEST_CASE("simulate runs every scene, reports its breaks and repeats itself byte for byte") {
  const fs::path tree = tree_file("box", 24);
  for (const char* scene : {"drop", "shoot", "wall"}) {
    INFO(scene);
    const fs::path glb[2] = {scratch(std::string(scene) + "-1.glb"), scratch(std::string(scene) + "-2.glb")};
    Run runs[2];
    for (int i = 0; i < 2; ++i) {
      runs[i] = run_shatter("simulate " + quoted(tree) + " --scene " + scene + " --steps 150 --json --record " +
                            quoted(glb[i]));
      REQUIRE(runs[i].exit_code == 0);
      CHECK(runs[i].err.empty());
    }
    const nlohmann::json out = nlohmann::json::parse(runs[0].out);
    CHECK(out["step_summaries"].size() == 150);
    CHECK(out["breaks"].size() > 0);
    CHECK(out["final"]["bodies_ever"].get<std::size_t>() > out["objects"].get<std::size_t>());
    CHECK(out["record"] == glb[0].string());
    // The two runs differ only in the recording's name.
    const nlohmann::json other = nlohmann::json::parse(runs[1].out);
    CHECK(out["breaks"] == other["breaks"]);
    CHECK(out["step_summaries"] == other["step_summaries"]);
    CHECK(out["final"] == other["final"]);
    CHECK(slurp(glb[0]) == slurp(glb[1]));
    CHECK(slurp(glb[0]).substr(0, 4) == "glTF");

    const Run text = run_shatter("simulate " + quoted(tree) + " --scene " + scene + " --steps 150 --print-every 50");
    REQUIRE(text.exit_code == 0);
    CHECK(text.out.find("break at t=") != std::string::npos);
    CHECK(text.out.find("step 100 t=") != std::string::npos);
    CHECK(text.out ==
          run_shatter("simulate " + quoted(tree) + " --scene " + scene + " --steps 150 --print-every 50").out);
  }
}

TEST_CASE("simulate refuses a damaged .shatter file with exit 3, one line and no recording") {
  const fs::path good = tree_file("box", 24);
  const std::string bytes = slurp(good);
  const fs::path dir = scratch("damaged");
  fs::create_directories(dir);
  std::vector<std::pair<std::string, std::string>> damaged;
  for (const std::size_t length : {std::size_t{0}, std::size_t{12}, bytes.size() / 2, bytes.size() - 1}) {
    damaged.emplace_back("truncated to " + std::to_string(length), bytes.substr(0, length));
  }
  for (const std::size_t at : {std::size_t{9}, bytes.size() / 3, bytes.size() - 20}) {
    std::string flipped = bytes;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x10);
    damaged.emplace_back("byte " + std::to_string(at) + " flipped", flipped);
  }
  for (const auto& [what, content] : damaged) {
    INFO(what);
    const fs::path file = dir / "damaged.shatter";
    std::ofstream(file, std::ios::binary) << content;
    const Run run = run_shatter("simulate " + quoted(file) + " --record " + quoted(dir / "out.glb"));
    CHECK(run.exit_code == 3);
    CHECK(is_one_error_line(run.err));
    CHECK(run.out.empty());
    CHECK_FALSE(fs::exists(dir / "out.glb"));
    CHECK(run_shatter("info " + quoted(file)).err == run.err);  // refused as info refuses it
  }
  const Run missing = run_shatter("simulate " + quoted(dir / "none.shatter"));
  CHECK(missing.exit_code == 4);
  CHECK(is_one_error_line(missing.err));
}

TEST_CASE("simulate reports the scene as run: relative defaults resolved for the object, given values as given") {
  const fs::path tree = tree_file("box", 24);  // 1 m x 0.8 m x 0.6 m
  const auto scene_of = [&](const std::string& arguments) {
    const Run run = run_shatter("simulate " + quoted(tree) + " --steps 1 --json " + arguments);
    REQUIRE(run.exit_code == 0);
    return nlohmann::json::parse(run.out)["scene"];
  };
  const nlohmann::json shoot = scene_of("--scene shoot");
  CHECK(shoot["object_size_m"].get<double>() == Approx(1.0));
  CHECK(shoot["object_mass_kg"].get<double>() == Approx(1000 * 0.48));
  CHECK(shoot["projectile_mass_kg"].get<double>() == Approx(480));
  CHECK(shoot["projectile_radius_m"].get<double>() == Approx(0.15));
  CHECK(shoot["projectile_speed_m_s"].get<double>() == Approx(2 * std::sqrt(9.81)));
  // The frailty at which an impulse of M sqrt(g L) breaks bonds within 0.45 L.
  CHECK(shoot["frailty_m3_per_N_s"].get<double>() == Approx(0.45 * 0.45 * 0.45 / (480 * std::sqrt(9.81))));
  CHECK(scene_of("--scene shoot --frailty 3e-4")["frailty_m3_per_N_s"].get<double>() == 3e-4);
  CHECK(scene_of("--scene drop")["height_m"].get<double>() == Approx(2.0));
  CHECK(scene_of("--scene drop --height 0")["height_m"].get<double>() == 0);
  const nlohmann::json given =
      scene_of("--scene wall --projectile-mass 50 --projectile-speed 40 --projectile-radius 0.1 --density 10");
  CHECK(given["projectile_mass_kg"].get<double>() == 50);
  CHECK(given["projectile_speed_m_s"].get<double>() == 40);
  CHECK(given["projectile_radius_m"].get<double>() == 0.1);
  CHECK(given["object_mass_kg"].get<double>() == Approx(10 * 0.48));
}

TEST_CASE("simulate's usage mistakes exit 2 and an unwritable recording exits 4, leaving nothing") {
  const fs::path tree = tree_file("box", 24);
  const fs::path dir = scratch("usage");
  fs::create_directories(dir);
  for (const std::string& arguments :
       {std::string("--scene fall"), std::string("--steps 0"), std::string("--density -1"), std::string("--bonds soft"),
        std::string("--impulse huge"), std::string("--method fast"), std::string("--time-step 0"),
        std::string("--record ") + quoted(dir / "run.txt"), std::string("--record ") + quoted(dir),
        std::string("--print-every 0"), std::string("--print-every -1"), std::string("--steps -1"), std::string("--no-such-option"),
        std::string("--projectile-mass 0"), std::string("--projectile-speed -1"), std::string("--height -1")}) {
    INFO(arguments);
    const Run run = run_shatter("simulate " + quoted(tree) + " " + arguments);
    CHECK(run.exit_code == 2);
    CHECK(is_one_error_line(run.err));
    CHECK(run.out.empty());
  }
  // A recording whose folder cannot be made (a file stands in its way).
  std::ofstream(dir / "blocker") << "x";
  const Run blocked =
      run_shatter("simulate " + quoted(tree) + " --steps 5 --record " + quoted(dir / "blocker" / "r.glb"));
  CHECK(blocked.exit_code == 4);
  CHECK(is_one_error_line(blocked.err));
  CHECK_FALSE(fs::exists(dir / "blocker" / "r.glb"));
}

TEST_CASE("simulate --help explains every option with its unit or default") {
  const Run help = run_shatter("simulate --help");
  REQUIRE(help.exit_code == 0);
  for (const char* option : {"--scene",
                             "--steps",
                             "--time-step",
                             "--solver-iterations",
                             "--no-sleep",
                             "--density",
                             "--frailty",
                             "--impact-speed",
                             "--hit-points",
                             "--bonds",
                             "--impulse",
                             "--min-distance",
                             "--friction",
                             "--restitution",
                             "--method",
                             "--margin",
                             "--height",
                             "--tilt",
                             "--projectile-mass",
                             "--projectile-speed",
                             "--projectile-radius",
                             "--wall-rows",
                             "--wall-columns",
                             "--json",
                             "--print-every",
                             "--record",
                             "--record-every",
                             "kg/m^3",
                             "m^3/(N s)",
                             "N s",
                             "m/s"}) {
    INFO(option);
    CHECK(help.out.find(option) != std::string::npos);
  }
}
