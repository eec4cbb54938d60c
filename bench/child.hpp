// A child process for the bench: `cdtgpu triangulate` (the e2e table) or a peer's executable (the peer table),
// timed from spawn to exit.
//
//   ChildRun r = spawn_child({"build/cdtgpu", "triangulate", ...}, {{"XDG_CACHE_HOME", dir}}, "log.txt", "s.json");
//   if (r.exit_code == 0) use(r.wall_ms, r.stats);
#pragma once
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace cdtgpu {

// One child run: its wall clock, exit status and (when it succeeded and wrote one) its stats JSON.
struct ChildRun {
  double wall_ms = 0;
  int exit_code = 0;  // 128 + signal when killed
  std::string log;    // the child's stdout + stderr
  nlohmann::ordered_json stats;
};

// posix_spawn of argv[0] with stdin from /dev/null and stdout + stderr into `log_path`; `env_overrides`
// replace or add variables of this process's environment. `stats_path` (may be empty): removed before the run,
// parsed after a successful one (exit_code -1 when it cannot be). `cwd`: the child's working directory.
ChildRun spawn_child(const std::vector<std::string>& argv, const std::map<std::string, std::string>& env_overrides,
                     const std::string& log_path, const std::string& stats_path, const std::string& cwd = {});

// The whole file as a string (empty when it cannot be read).
std::string read_text(const std::string& path);

}  // namespace cdtgpu
