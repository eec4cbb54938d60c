#include "cli/job_file.hpp"

#include <fstream>
#include <iostream>

#include "core/error.hpp"

namespace cdtgpu {

std::vector<std::string> split_job_line(const std::string& line) {
  std::vector<std::string> words;
  std::string word;
  bool in_word = false;  // a word has begun (an empty '' or "" is a word too)
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == ' ' || c == '\t' || c == '\r') {
      if (in_word) words.push_back(std::move(word));
      word.clear();
      in_word = false;
    } else if (c == '#' && !in_word) {
      break;
    } else if (c == '\\') {
      if (i + 1 == line.size()) throw UsageError("the line ends in a backslash");
      word += line[++i];
      in_word = true;
    } else if (c == '\'') {
      const size_t end = line.find('\'', i + 1);
      if (end == std::string::npos) throw UsageError("a single quote is not closed");
      word += line.substr(i + 1, end - i - 1);
      i = end;
      in_word = true;
    } else if (c == '"') {
      size_t j = i + 1;
      for (; j < line.size() && line[j] != '"'; ++j) {
        if (line[j] == '\\' && j + 1 < line.size() && std::string("\"\\$`").find(line[j + 1]) != std::string::npos)
          ++j;
        word += line[j];
      }
      if (j == line.size()) throw UsageError("a double quote is not closed");
      i = j;
      in_word = true;
    } else {
      word += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(std::move(word));
  return words;
}

std::vector<JobLine> read_job_file(const std::string& path) {
  std::ifstream file;
  if (path != "-") {
    file.open(path);
    if (!file) throw UsageError(path + ": cannot read the job file");
  }
  std::istream& in = path == "-" ? std::cin : file;
  std::vector<JobLine> jobs;
  std::string text;
  for (int number = 1; std::getline(in, text); ++number) {
    JobLine j;
    j.number = number;
    try {
      j.words = split_job_line(text);
      if (j.words.empty()) continue;
    } catch (const UsageError& e) {
      j.error = e.what();
    }
    jobs.push_back(std::move(j));
  }
  if (in.bad()) throw UsageError((path == "-" ? std::string("stdin") : path) + ": cannot read the job file");
  return jobs;
}

}  // namespace cdtgpu
