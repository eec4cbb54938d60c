// A batch's job file: one `cdtgpu triangulate` command line per line, split into words like a shell does
// (without expansions), so that lines can be copied from scripts.
//
//   for (const JobLine& j : read_job_file("jobs.txt"))     // or "-": stdin
//     if (j.error.empty()) use(j.number, j.words);         // else the line's quoting was bad: j.error says how
//
// Quoting: blanks separate words; '...' keeps everything literally; "..." keeps everything but \" \\ \$ \`
// (the second character); outside quotes a backslash keeps the next character. A # at the start of a
// word starts a comment. Blank and comment-only lines are left out.
#pragma once
#include <string>
#include <vector>

namespace cdtgpu {

struct JobLine {
  int number = 0;                  // 1-based line number in the file
  std::vector<std::string> words;  // empty when error is set
  std::string error;               // bad quoting: what is wrong
};

// Throws UsageError (unterminated quote, a backslash at the end of the line).
std::vector<std::string> split_job_line(const std::string& line);

// Throws UsageError when the file cannot be read.
std::vector<JobLine> read_job_file(const std::string& path);

}  // namespace cdtgpu
