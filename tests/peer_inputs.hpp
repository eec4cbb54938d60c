// Where the peer inputs are (artem-ogre/CDT's test suite, 30+ text files; ../shared/data/cdt-peer-inputs/README
// gives their source and license): $CDTGPU_PEER_INPUTS, else ../shared/data/cdt-peer-inputs beside the
// repository. They are not in the repository: a test that needs them skips, naming what is missing, so a fresh
// clone with nothing beside it passes.
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

namespace cdtgpu {

inline std::filesystem::path peer_inputs_dir() {
  const char* env = std::getenv("CDTGPU_PEER_INPUTS");
  return env && *env ? std::filesystem::path(env) : std::filesystem::path(CDTGPU_SHARED_DATA) / "cdt-peer-inputs";
}

// The .txt files there, sorted; empty when the folder is absent.
inline std::vector<std::filesystem::path> peer_input_files() {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(peer_inputs_dir(), ec))
    if (e.path().extension() == ".txt") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

inline std::string peer_inputs_missing() {
  return "no peer inputs at " + peer_inputs_dir().string() +
         " (artem-ogre/CDT's test inputs, in ../shared/data beside the repository; CDTGPU_PEER_INPUTS may name a copy)";
}

}  // namespace cdtgpu

// At the top of a test that reads the peer inputs.
#define CDTGPU_SKIP_WITHOUT_PEER_INPUTS() \
  if (::cdtgpu::peer_input_files().empty()) GTEST_SKIP() << ::cdtgpu::peer_inputs_missing()
