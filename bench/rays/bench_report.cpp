// SPDX-License-Identifier: MIT
#include "bench_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "boxtree/error.h"

#ifndef BOXTREE_BENCH_COMPILER
#define BOXTREE_BENCH_COMPILER "unknown"
#endif
#ifndef BOXTREE_BENCH_FLAGS
#define BOXTREE_BENCH_FLAGS "unknown"
#endif

namespace boxtree::bench {
namespace {

// The value after "key" and a colon in the first matching line of a /proc file.
std::string proc_field(const std::string& file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) != 0) continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    auto value = line.substr(colon + 1);
    const auto first = value.find_first_not_of(" \t");
    return first == std::string::npos ? std::string() : value.substr(first);
  }
  return {};
}

nlohmann::json number_or_null(double x) { return std::isfinite(x) ? nlohmann::json(x) : nlohmann::json(nullptr); }

}  // namespace

Row compare(std::string section, std::string case_name, std::string metric, std::string method, double boxtree,
            std::string peer, double peer_value) {
  Row r{std::move(section), std::move(case_name), std::move(metric), std::move(method), boxtree,
        std::move(peer),    peer_value,           std::nullopt};
  if (peer_value != 0 && std::isfinite(peer_value) && std::isfinite(boxtree)) r.ratio = boxtree / peer_value;
  return r;
}

void write_json(const std::string& path, const std::vector<Row>& rows) {
  nlohmann::json out = nlohmann::json::array();
  for (const Row& r : rows) {
    out.push_back({{"section", r.section},
                   {"case", r.case_name},
                   {"metric", r.metric},
                   {"boxtree_method", r.boxtree_method},
                   {"boxtree", number_or_null(r.boxtree)},
                   {"peer", r.peer},
                   {"peer_value", number_or_null(r.peer_value)},
                   {"ratio", r.ratio ? number_or_null(*r.ratio) : nlohmann::json(nullptr)}});
  }
  write_text(path, out.dump(1) + "\n");
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream file(path);
  file << text;
  if (!file) throw Error(path + ": cannot write");
}

std::string machine_markdown(const std::string& peers) {
  std::ostringstream s;
  const std::string cpu = proc_field("/proc/cpuinfo", "model name");
  const std::string mem = proc_field("/proc/meminfo", "MemTotal");
  std::string load;
  std::getline(std::ifstream("/proc/loadavg") >> std::ws, load);
  const std::time_t now = std::time(nullptr);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  s << "- Machine: " << (cpu.empty() ? "unknown CPU" : cpu) << ", " << std::thread::hardware_concurrency()
    << " hardware threads, " << mem << " RAM; load average at start: " << load
    << " (a shared machine: compare the ratios, not the absolute figures)\n";
  s << "- Compiler: " << BOXTREE_BENCH_COMPILER << ", flags `" << BOXTREE_BENCH_FLAGS
    << "`; every engine runs single-threaded\n";
  s << "- Peers: " << peers << "\n";
  s << "- Date: " << date << "\n";
  return s.str();
}

std::uint64_t peak_rss_bytes() {
  const std::string hwm = proc_field("/proc/self/status", "VmHWM");  // "123456 kB"
  return hwm.empty() ? 0 : std::uint64_t(std::stoull(hwm)) * 1024;
}

std::string with_commas(std::uint64_t x) {
  std::string s = std::to_string(x);
  for (int i = int(s.size()) - 3; i > 0; i -= 3) s.insert(std::size_t(i), ",");
  return s;
}

std::string format(const char* fmt, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, x);
  return buf;
}

std::string table(const std::vector<std::vector<std::string>>& cells, bool markdown) {
  std::vector<std::size_t> width(cells.front().size(), 0);
  for (const auto& row : cells)
    for (std::size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
  std::ostringstream out;
  for (std::size_t r = 0; r < cells.size(); ++r) {
    for (std::size_t c = 0; c < cells[r].size(); ++c) {
      const std::string& cell = cells[r][c];
      if (markdown)
        out << "| " << cell << " ";
      else
        out << (c ? "  " : "") << cell << std::string(width[c] - cell.size(), ' ');
    }
    out << (markdown ? "|\n" : "\n");
    if (markdown && r == 0) {
      for (std::size_t c = 0; c < cells[r].size(); ++c) out << (c ? "|---:" : "|---");
      out << "|\n";
    }
  }
  return out.str();
}

}  // namespace boxtree::bench
