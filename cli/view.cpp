#include "view.hpp"

#include <httplib.h>
#include <nlohmann/json.hpp>
#include <pthread.h>
#include <sys/socket.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>

#include "fracture.hpp"
#include "shatter/kernel/error.hpp"
#include "shatter/meshtree/build.hpp"
#include "shatter/formats/export.hpp"
#include "shatter/formats/file.hpp"
#include "shatter/formats/tinygltf.hpp"
#include "errors.hpp"
#include "huge_page_objects.hpp"
#include "tree_stats_json.hpp"
#include "view_original.hpp"
#include "viewer_page.hpp"
#include "json_text.hpp"

namespace shatter::cli {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;
using Clock = std::chrono::steady_clock;

constexpr const char* json_type = "application/json";

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError("cannot open " + path.string() + ": " + std::strerror(errno));
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad() || fs::is_directory(path)) throw IoError("cannot read " + path.string());
  return std::move(bytes).str();
}

// A .glb is checked as glTF 2.0 binary before it is served, so a damaged file
// is refused here with tinygltf's reason, not shown as an empty page.
void require_glb(const fs::path& path, const std::string& bytes) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string error, warning;
  if (bytes.size() > 0xFFFFFFFFu ||
      !loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(bytes.data()),
                                   static_cast<unsigned int>(bytes.size()))) {
    std::string reason = error.empty() ? "not a glTF 2.0 binary" : error;
    while (!reason.empty() && std::isspace(static_cast<unsigned char>(reason.back()))) reason.pop_back();
    throw CorruptFileError(path.string() + ": not a GLB the viewer can show: " + reason);
  }
}

// The tree the editor rebuilds from and what is shown now, shared by the
// server's threads and the fracture job.
class Session {
 public:
  Session(std::string file, std::optional<MeshTree> tree, std::string glb, std::string original_name = {})
      : file_(std::move(file)),
        editable_(tree.has_value()),
        original_name_(std::move(original_name)),
        glb_(std::make_shared<const std::string>(std::move(glb))) {
    if (tree) {
      root_ = std::move(tree->nodes[0].mesh);
      recipe_ = tree->recipe;
    }
  }

  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  ~Session() {
    // A job still running at the stop cannot be interrupted (the builder has no
    // cancellation); run_view ends the process without waiting for it.
    if (!job_.joinable()) return;
    if (running()) {
      job_.detach();
    } else {
      job_.join();
    }
  }

  std::shared_ptr<const std::string> glb() const {
    const std::lock_guard lock(mutex_);
    return glb_;
  }

  json session_json() const {
    const std::lock_guard lock(mutex_);
    json out{{"file", file_}, {"kind", editable_ ? "tree" : "glb"}, {"editable", editable_},
             {"generation", generation_}};
    if (editable_) {
      json options = recipe_json(recipe_);
      options["seed"] = std::to_string(recipe_.seed);  // beyond 2^53 a JavaScript number would round it
      out["options"] = std::move(options);
    }
    if (!original_name_.empty()) out["original"] = {{"file", original_name_}};
    return out;
  }

  bool running() const { return state_ == State::running; }

  json job_json() const {
    const std::lock_guard lock(mutex_);
    json out{{"state", state_name()},
             {"leaves_done", leaves_done_.load(std::memory_order_relaxed)},
             {"fragments", job_recipe_.fragments},
             {"generation", generation_}};
    if (state_ == State::done) {
      out["leaves"] = leaves_;
      out["seconds"] = seconds_;
    }
    if (state_ == State::failed) out["error"] = error_;
    return out;
  }

  /// Starts a fracture of the root solid by `recipe` in the background.
  /// Returns an error message instead when the file is not a tree or a job runs.
  std::optional<std::string> start(const TreeRecipe& recipe) {
    const std::lock_guard lock(mutex_);
    if (!editable_) return "this file is a GLB: only a .shatter file can be fractured again";
    if (state_ == State::running) return "a fracture is already running; wait for it to finish";
    if (job_.joinable()) job_.join();  // finished: nothing to wait for
    state_ = State::running;
    job_recipe_ = recipe;
    leaves_done_.store(0, std::memory_order_relaxed);
    job_ = std::thread([this, recipe] { run_job(recipe); });
    return std::nullopt;
  }

 private:
  enum class State { idle, running, done, failed };

  const char* state_name() const {
    switch (state_) {
      case State::idle: return "idle";
      case State::running: return "running";
      case State::done: return "done";
      case State::failed: return "failed";
    }
    return "unknown";
  }

  void run_job(const TreeRecipe& recipe) {
    const Clock::time_point start = Clock::now();
    try {
      BuildRunOptions run;
      run.progress = [this](std::size_t done) {
        // Reports come from several workers, possibly out of order: keep the largest.
        std::size_t seen = leaves_done_.load(std::memory_order_relaxed);
        while (seen < done && !leaves_done_.compare_exchange_weak(seen, done, std::memory_order_relaxed)) {
        }
      };
      const MeshTree tree = build_mesh_tree(root_, recipe, run);
      const std::vector<NodeIndex> all = select_nodes(tree, NodeSelection{NodeSelectionKind::all});
      auto glb = std::make_shared<const std::string>(encode_glb(tree, all));
      const std::lock_guard lock(mutex_);
      glb_ = std::move(glb);
      recipe_ = tree.recipe;
      leaves_ = tree.leaf_count();
      // The progress counted the leaves of cuts the build undid at the end (the
      // count passing N): done, the tree's own count is the count.
      leaves_done_.store(leaves_, std::memory_order_relaxed);
      seconds_ = std::chrono::duration<double>(Clock::now() - start).count();
      ++generation_;
      state_ = State::done;
    } catch (...) {
      // The same words the fracture command would print after "error: ".
      const Failure failure = failure_of(std::current_exception());
      const std::lock_guard lock(mutex_);
      error_ = failure.message;
      state_ = State::failed;
    }
  }

  const std::string file_;
  const bool editable_;
  const std::string original_name_;  // of --original; empty without it
  Mesh root_;  // the tree's root solid: what the editor fractures again
  mutable std::mutex mutex_;
  std::shared_ptr<const std::string> glb_;  // guarded by mutex_
  TreeRecipe recipe_;                       // of the tree shown; guarded by mutex_
  std::uint64_t generation_ = 0;            // guarded by mutex_; counts trees shown
  std::atomic<State> state_{State::idle};
  TreeRecipe job_recipe_;  // guarded by mutex_
  std::atomic<std::size_t> leaves_done_{0};
  std::size_t leaves_ = 0;  // of the last finished job; guarded by mutex_
  double seconds_ = 0;      // guarded by mutex_
  std::string error_;       // guarded by mutex_
  std::thread job_;
};

// A whole number from a JSON string or number: the page sends strings, so a
// seed beyond 2^53 arrives exactly.
std::optional<std::uint64_t> whole_number(const json& value) {
  if (value.is_number_unsigned()) return value.get<std::uint64_t>();
  if (!value.is_string()) return std::nullopt;
  const std::string& text = value.get_ref<const std::string&>();
  return parse_whole_number(text);
}

// The most fragments the editor builds: a page shows no more usefully, and a
// request for 1e9 (accepted up to 2^32 - 1 until 2026-12-07, found by a sweep)
// grew the server by 450 MB/s until the kernel killed it, with no way to cancel.
// `shatter fracture` takes more.
constexpr std::uint64_t editor_fragment_limit = 65536;

// The recipe a POST /api/fracture asks for, checked as the fracture command
// checks its flags. Throws UsageError with the message for the page.
TreeRecipe requested_recipe(const std::string& body) {
  const json request = json::parse(body, nullptr, false);
  if (request.is_discarded() || !request.is_object()) throw UsageError("the request is not a JSON object");
  const std::optional<std::uint64_t> fragments = whole_number(request.value("fragments", json()));
  if (!fragments || *fragments < 1 || *fragments > editor_fragment_limit) {
    throw UsageError("fragments must be a whole number from 1 to " + std::to_string(editor_fragment_limit) +
                     " in the editor (shatter fracture takes more)");
  }
  const std::optional<std::uint64_t> seed = whole_number(request.value("seed", json("1")));
  if (!seed) throw UsageError("seed must be a whole number from 0 to 18446744073709551615");
  // A strategy that is not a string is the page's mistake, not the server's: a
  // 400 like the others (it was a 500 from json's type error, found by a sweep).
  const json strategy = request.value("strategy", json("thesis"));
  if (!strategy.is_string()) throw UsageError("strategy must be thesis, balanced or axis, as a string");
  return tree_recipe_from(*fragments, *seed, strategy.get_ref<const std::string&>(), "");
}

void send_json(httplib::Response& response, int status, const json& body) {
  response.status = status;
  response.set_header("Cache-Control", "no-store");
  response.set_content(json_text(body), json_type);
}

// `original`: the body of GET /api/original, or empty without --original (the route is then not served).
void add_routes(httplib::Server& server, Session& session, const std::string& page, const std::string& original) {
  server.Get("/", [&page](const httplib::Request&, httplib::Response& response) {
    response.set_content(page, "text/html; charset=utf-8");
  });
  server.Get("/model.glb", [&session](const httplib::Request&, httplib::Response& response) {
    const std::shared_ptr<const std::string> glb = session.glb();
    response.set_header("Cache-Control", "no-store");
    response.set_content(*glb, "model/gltf-binary");
  });
  server.Get("/api/session", [&session](const httplib::Request&, httplib::Response& response) {
    send_json(response, 200, session.session_json());
  });
  if (!original.empty()) {
    server.Get("/api/original", [&original](const httplib::Request&, httplib::Response& response) {
      response.set_content(original, json_type);
    });
  }
  server.Get("/api/fracture", [&session](const httplib::Request&, httplib::Response& response) {
    send_json(response, 200, session.job_json());
  });
  server.Post("/api/fracture", [&session](const httplib::Request& request, httplib::Response& response) {
    TreeRecipe recipe;
    try {
      recipe = requested_recipe(request.body);
    } catch (const UsageError& e) {
      send_json(response, 400, {{"error", e.what()}});
      return;
    }
    if (const std::optional<std::string> refused = session.start(recipe)) {
      send_json(response, 409, {{"error", *refused}});
      return;
    }
    send_json(response, 202, session.job_json());
  });
  // Every other path, and a handler's failure, answers JSON the page can show.
  server.set_error_handler([](const httplib::Request& request, httplib::Response& response) {
    if (response.status == 404) {
      send_json(response, 404, {{"error", "no such page: " + request.path}});
    } else if (response.body.empty()) {
      send_json(response, response.status, {{"error", "the server answered " + std::to_string(response.status)}});
    }
  });
  server.set_exception_handler([](const httplib::Request&, httplib::Response& response, std::exception_ptr error) {
    send_json(response, 500, {{"error", failure_of(error).message}});
  });
}

}  // namespace

Command add_view_command(CLI::App& app) {
  auto args = std::make_shared<ViewArgs>();
  CLI::App* command = app.add_subcommand(
      "view",
      "Open the viewer: serve it and the file on 127.0.0.1 (this machine only) and print the address to open in a "
      "browser; Ctrl-C stops. The page explodes the fragments, shows the tree level by level, colours fragments, "
      "draws bonds, describes a clicked fragment as `info --nodes` does, and replays `simulate --record` files. For "
      "a .shatter file it also has an editor that fractures the tree's root solid again with other fragments, seed or "
      "strategy (nothing is written to disk). For a page that needs no server, see `export --format html`.");
  command->add_option("file", args->input,
                      "A mesh tree (.shatter; every level is shown) or a glTF binary (.glb) from `export` or "
                      "`simulate --record`")
      ->required();
  command->add_option("--original", args->original,
                      "With a .shatter file built with --repair: the mesh file it was built from (read as fracture "
                      "reads it). The page gets an \"Original input\" panel with the repair report and a switch that "
                      "draws the file as it is beside the tree's root, its boundary edges, non-manifold edges and "
                      "self-intersecting triangles highlighted. Refused with one line when the file cannot be read or "
                      "drawn, or its bounding box does not hold the root's (equals it, for a tree built without "
                      "--repair)");
  command->add_option("--port", args->port, "Port on 127.0.0.1 to listen on; 0 picks a free one")
      ->capture_default_str();
  return {command, [args] { return run_view(*args); }};
}

int run_view(const ViewArgs& args) {
  // SIGINT and SIGTERM are taken by one thread (sigwait), never by a handler,
  // so stopping the server happens in ordinary code. They are blocked first of
  // all, before reading the file starts the thread pool's workers: every thread
  // inherits the mask, so none can take a stop signal and end the process there
  // (reading a tree runs on the pool; while the mask was set only after the
  // read, Ctrl-C killed the server). One sent while the file is read waits, and
  // stops the server as soon as it listens.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  require_viewer("view");
  const fs::path path(args.input);
  const std::string extension = lower_extension(path);
  if (extension != ".shatter" && extension != ".glb") {
    throw UsageError("view shows a .shatter or .glb file, got '" + args.input + "'");
  }
  if (!args.original.empty() && extension != ".shatter") {
    throw UsageError("--original goes with a .shatter file (the tree built from it), not with '" + args.input + "'");
  }
  std::unique_ptr<Session> session;
  std::string original;  // the answer of GET /api/original
  if (extension == ".shatter") {
    keep_small_objects_on_huge_pages();
    MeshTree tree = read_shatter_file(path);
    if (tree.nodes.empty()) throw CorruptFileError(args.input + ": the tree has no nodes");
    std::string original_name;
    if (!args.original.empty()) {
      const OriginalInput input = read_original_input(args.original, tree.nodes[0].mesh, tree.input_repair);
      original = json_text(original_json(input, tree.input_repair));
      original_name = input.name;
    }
    std::string glb = encode_glb(tree, select_nodes(tree, NodeSelection{NodeSelectionKind::all}));
    session = std::make_unique<Session>(path.filename().string(), std::move(tree), std::move(glb),
                                        std::move(original_name));
  } else {
    std::string glb = read_bytes(path);
    require_glb(path, glb);
    session = std::make_unique<Session>(path.filename().string(), std::nullopt, std::move(glb));
  }
  const std::string page = served_viewer_page();

  // A browser that closes a connection while a model is being sent must not end the server.
  ::signal(SIGPIPE, SIG_IGN);

  httplib::Server server;
  // httplib's default also sets SO_REUSEPORT, which would let a second server
  // share the port (and its requests) instead of failing; SO_REUSEADDR alone
  // only allows a restart while old connections linger.
  server.set_socket_options([](socket_t socket) {
    const int yes = 1;
    ::setsockopt(socket, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
  });
  add_routes(server, *session, page, original);
  constexpr const char* host = "127.0.0.1";
  int port = args.port;
  if (args.port == 0) {
    port = server.bind_to_any_port(host);
  } else if (!server.bind_to_port(host, args.port)) {
    port = -1;
  }
  if (port <= 0) {
    throw IoError("cannot listen on " + std::string(host) + ":" + std::to_string(args.port) +
                  " (in use, or not allowed); choose another with --port, or --port 0 for any free one");
  }

  std::atomic<bool> stopped{false};
  std::atomic<bool> signalled{false};
  std::thread signal_thread([&] {
    const timespec tick{0, 200'000'000};
    while (!stopped.load()) {
      if (sigtimedwait(&stop_signals, nullptr, &tick) > 0) {
        signalled.store(true);
        server.stop();
        return;
      }
    }
  });
  std::cout << "shatter view: " << args.input << " at http://" << host << ":" << port << "/ (Ctrl-C stops)"
            << std::endl;
  server.listen_after_bind();
  stopped.store(true);
  signal_thread.join();
  if (!signalled.load()) throw IoError("the server on " + std::string(host) + ":" + std::to_string(port) + " failed");
  std::cout << "shatter view: stopped" << std::endl;
  if (session->running()) {
    // The builder cannot be interrupted and the server is gone: end without
    // waiting for the abandoned job (it writes nothing).
    std::cout.flush();
    std::_Exit(static_cast<int>(ExitCode::ok));
  }
  return static_cast<int>(ExitCode::ok);
}

}  // namespace shatter::cli
