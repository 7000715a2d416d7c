// likeness bench --only io: reader speed on a synthetic 300k-point scan in
// every PLY flavour and XYZ, plus the real OBJ/VTK scans and a photo when
// ../shared/data (or --data DIR) is present. Median of 5 runs (1 with --quick).
// Then the memory a 1M-point OBJ and XYZ take to load, held whole and read
// (as the page's worker did before issue 39) or pushed in 8 MB slices into
// the stream reader (as it does now): the peak resident memory over the
// start (Linux only).
#include "command.h"
#include "timing.h"

#include "io/io.h"
#include "io/scan_stream.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <cstring>
#include <fstream>
#include <functional>
#include <string>
#include <unistd.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace lk::cli {
namespace {



// A 300k-point helix-wrapped cylinder with normals, like a dense range scan.
PointCloud synthetic_scan(int n) {
  PointCloud c;
  c.positions.reserve(n);
  c.normals.reserve(n);
  for (int i = 0; i < n; ++i) {
    const double a = i * 0.0137, h = i * 1e-3;
    c.positions.push_back(Vec3(100 * std::cos(a), 100 * std::sin(a), h));
    c.normals.push_back(Vec3(std::cos(a), std::sin(a), 0));
  }
  return c;
}

void row(const std::string& what, size_t bytes, Timing t, bool ok) {
  std::printf("   %-44s %8.2f MB %9.2f ms %9.2f ms %8.1f MB/s %s\n", what.c_str(), bytes / 1e6, t.wall_ms, t.cpu_ms,
              t.cpu_ms > 0 ? bytes / 1e3 / t.cpu_ms : 0.0, ok ? "" : "(FAILED)");
}

// Ascii PLY as scanners write it: 6 decimals per value.
Bytes ascii_ply_6_decimals(const PointCloud& c) {
  std::string s = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(c.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
                  "property float nz\nend_header\n";
  char line[160];
  for (int i = 0; i < c.size(); ++i) {
    const Vec3 &p = c.positions[i], &n = c.normals[i];
    std::snprintf(line, sizeof(line), "%.6f %.6f %.6f %.6f %.6f %.6f\n", p.x(), p.y(), p.z(), n.x(), n.y(), n.z());
    s += line;
  }
  return Bytes(s.begin(), s.end());
}

// A field of /proc/self/status in kB (-1 when unreadable).
long status_kb(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const size_t n = std::strlen(key);
  while (std::getline(f, line))
    if (line.compare(0, n, key) == 0 && line.size() > n && line[n] == ':') return std::atol(line.c_str() + n + 1);
  return -1;
}

// Runs load with the peak resident memory reset (Linux: clear_refs 5), and
// returns the peak over the memory resident before it, in MB (-1: unknown).
double peak_mb(const std::function<bool()>& load, bool& ok) {
#if defined(__GLIBC__)
  // Large blocks from mmap, given back when freed, and the heap's free
  // memory released first: what was freed before does not hide the peak.
  mallopt(M_MMAP_THRESHOLD, 256 * 1024);
  malloc_trim(0);
#endif
  {
    std::ofstream reset("/proc/self/clear_refs");
    reset << "5";
    if (!reset) return -1;
  }
  const long base = status_kb("VmRSS");
  ok = load();
  const long peak = status_kb("VmHWM");
  return base < 0 || peak < 0 ? -1 : (peak - base) / 1024.0;
}

// The scan as text the way scanners write it, 6 decimals a value.
std::string text_scan(const PointCloud& c, bool obj) {
  std::string s;
  char line[128];
  for (int i = 0; i < c.size(); ++i) {
    const Vec3 &p = c.positions[i], &n = c.normals[i];
    if (obj) std::snprintf(line, sizeof(line), "v %.6f %.6f %.6f\n", p.x(), p.y(), p.z());
    else std::snprintf(line, sizeof(line), "%.6f %.6f %.6f %.6f %.6f %.6f\n", p.x(), p.y(), p.z(), n.x(), n.y(), n.z());
    s += line;
  }
  if (obj)
    for (int i = 0; i < c.size(); ++i) {
      const Vec3& n = c.normals[i];
      std::snprintf(line, sizeof(line), "vn %.6f %.6f %.6f\n", n.x(), n.y(), n.z());
      s += line;
    }
  return s;
}

int run_memory_rows(int n) {
  int failures = 0;
  std::printf("   %-44s %11s %12s\n", "load (the page's worker, natively)", "size", "peak RSS");
  for (bool obj : {true, false}) {
    const std::string path = "/tmp/likeness_bench_io_" + std::to_string(::getpid()) + (obj ? ".obj" : ".xyz");
    size_t size = 0;
    {
      const std::string text = text_scan(synthetic_scan(n), obj);
      size = text.size();
      if (!write_file(path, text)) {
        std::printf("   (memory rows skipped: cannot write %s)\n", path.c_str());
        return 0;
      }
    }
    const std::string what = std::string(obj ? "OBJ" : "XYZ") + ", " + std::to_string(n / 1000000) + "M points + normals";
    bool ok = false;
    // Before issue 39: the bytes gathered whole, then read_geometry (a mesh
    // and a cloud copy of the points).
    const double whole = peak_mb([&] {
      Bytes bytes;
      TriMesh m;
      PointCloud c;
      GeometryKind kind;
      return read_file(path, bytes).ok() && read_geometry(path, bytes.data(), bytes.size(), m, c, kind).ok() &&
             m.num_vertices() == n;
    }, ok);
    failures += !ok;
    std::printf("   %-44s %8.1f MB %9.1f MB%s\n", (what + ", whole").c_str(), size / 1e6, whole, ok ? "" : " (FAILED)");
    // Now: 8 MB slices pushed into the stream reader, the mesh's arrays only.
    const double streamed = peak_mb([&] {
      ScanStreamReader reader(path, size);
      std::FILE* f = std::fopen(path.c_str(), "rb");
      if (!f) return false;
      std::vector<std::uint8_t> slice(8 << 20);
      bool pushed = true;
      for (size_t got; pushed && (got = std::fread(slice.data(), 1, slice.size(), f)) > 0;)
        pushed = reader.push(slice.data(), got).ok();
      std::fclose(f);
      TriMesh m;
      GeometryKind kind;
      return pushed && reader.finish(m, kind).ok() && m.num_vertices() == n;
    }, ok);
    failures += !ok;
    std::printf("   %-44s %8.1f MB %9.1f MB%s\n", (what + ", streamed").c_str(), size / 1e6, streamed, ok ? "" : " (FAILED)");
    std::remove(path.c_str());
  }
  return failures;
}

int run_io_bench(const Args& args) {
  const int reps = args.has("quick") ? 1 : 5;
  const int n = 300000;
  const PointCloud cloud = synthetic_scan(n);
  PointCloud xyz_only;
  xyz_only.positions = cloud.positions;
  std::printf("   %-44s %11s %12s %12s %13s\n", "input", "size", "wall (med)", "CPU (med)", "MB/CPU-s");
  int failures = 0;
  struct Case {
    std::string name;
    Bytes bytes;
  };
  std::vector<Case> cases;
  cases.push_back({"PLY binary LE, 300k points xyz (float)", write_ply(xyz_only)});
  cases.push_back({"PLY binary LE, 300k points xyz+normals", write_ply(cloud)});
  cases.push_back({"PLY ascii, 300k points xyz (17 digits)", write_ply(xyz_only, true)});
  cases.push_back({"PLY ascii, 300k points xyz+normals (17 dig.)", write_ply(cloud, true)});
  cases.push_back({"PLY ascii, 300k points xyz+normals (%.6f)", ascii_ply_6_decimals(cloud)});
  for (const Case& c : cases) {
    TriMesh m;
    GeometryKind kind;
    bool ok = false;
    const Timing ms = median_ms(reps, [&] { return read_ply(c.bytes.data(), c.bytes.size(), m, kind).ok() && m.num_vertices() == n; }, ok);
    row(c.name, c.bytes.size(), ms, ok);
    failures += !ok;
  }
  {
    const std::string text = write_xyz(cloud);
    PointCloud back;
    bool ok = false;
    const Timing ms = median_ms(reps, [&] {
      return read_xyz(reinterpret_cast<const std::uint8_t*>(text.data()), text.size(), back).ok() && back.size() == n;
    }, ok);
    row("XYZ, 300k points xyz+normals", text.size(), ms, ok);
    failures += !ok;
  }
  const std::string shared = args.get("data", "../shared/data");
  struct FileCase {
    std::string label, path;
    bool image;
  };
  const std::vector<FileCase> files = {
      {"OBJ james.obj (6,393 v, 12,228 f)", shared + "/head_scans/james_menpo3d/james.obj", false},
      {"VTK fran_cut.vtk (2,205 v, 4,224 f)", shared + "/head_scans/fran_cyberware/fran_cut.vtk", false},
      {"JPEG Kira 0001.jpg (1800x1200)", shared + "/multiview_faces/keentools_kira/0001.jpg", true},
  };
  for (const FileCase& f : files) {
    Bytes bytes;
    if (!read_file(f.path, bytes)) {
      std::printf("   %-44s (skipped: %s absent)\n", f.label.c_str(), f.path.c_str());
      continue;
    }
    bool ok = false;
    Timing ms;
    if (f.image) {
      Image im;
      ms = median_ms(reps, [&] { return read_image(bytes.data(), bytes.size(), im).ok(); }, ok);
    } else {
      TriMesh m;
      PointCloud c;
      GeometryKind kind;
      ms = median_ms(reps, [&] { return read_geometry(f.path, bytes.data(), bytes.size(), m, c, kind).ok(); }, ok);
    }
    row(f.label, bytes.size(), ms, ok);
    failures += !ok;
  }
  failures += run_memory_rows(1000000);
  return failures ? 1 : 0;
}

BenchRegistrar reg({"io", "reader speed: 300k-point PLY (binary/ascii), XYZ, real OBJ/VTK scans, JPEG photo; "
                    "the memory a 1M-point OBJ and XYZ take to load, whole and streamed",
                    run_io_bench});

}  // namespace
}  // namespace lk::cli
