#include "cairn/io/compressed_file.hpp"

#include <bzlib.h>
#include <zlib.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>

#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::io {
namespace {

std::string read_raw(const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw ParseError(path, 0, std::string("cannot open file: ") + std::strerror(errno));
  std::string out;
  char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, file.get())) > 0) out.append(buffer, n);
  if (std::ferror(file.get())) throw ParseError(path, 0, "read error");
  return out;
}

void check_size(const std::string& path, std::size_t size, std::size_t max_bytes) {
  if (size > max_bytes) {
    throw ParseError(path, 0, "decompressed data exceeds " + std::to_string(max_bytes) + " bytes: refusing to read it");
  }
}

std::string gunzip(const std::string& path, std::size_t max_bytes) {
  gzFile file = gzopen(path.c_str(), "rb");
  if (file == nullptr) throw ParseError(path, 0, std::string("cannot open gzip file: ") + std::strerror(errno));
  std::string out;
  char buffer[1 << 16];
  while (true) {
    const int n = gzread(file, buffer, sizeof buffer);
    if (n < 0) {
      int code = 0;
      const std::string message = gzerror(file, &code);
      gzclose(file);
      throw ParseError(path, 0, "gzip data is corrupt: " + message);
    }
    if (n == 0) break;
    out.append(buffer, static_cast<std::size_t>(n));
    check_size(path, out.size(), max_bytes);
  }
  // gzread stops quietly at a truncated stream; gzclose_r then reports Z_BUF_ERROR.
  const int status = gzclose_r(file);
  if (status != Z_OK) throw ParseError(path, 0, "gzip data is truncated (the stream ends before its trailer)");
  return out;
}

std::string bunzip2(const std::string& path, std::size_t max_bytes) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw ParseError(path, 0, std::string("cannot open bzip2 file: ") + std::strerror(errno));
  std::string out;
  char buffer[1 << 16];
  // Concatenated bzip2 streams (as pbzip2 writes) are read one after the other.
  std::string unused;
  while (true) {
    int error = BZ_OK;
    BZFILE* bz = BZ2_bzReadOpen(&error, file.get(), 0, 0, unused.empty() ? nullptr : unused.data(),
                                static_cast<int>(unused.size()));
    if (error != BZ_OK) throw ParseError(path, 0, "cannot read bzip2 data");
    while (error == BZ_OK) {
      const int n = BZ2_bzRead(&error, bz, buffer, sizeof buffer);
      if (error == BZ_OK || error == BZ_STREAM_END) {
        out.append(buffer, static_cast<std::size_t>(n));
        check_size(path, out.size(), max_bytes);
      }
    }
    if (error != BZ_STREAM_END) {
      BZ2_bzReadClose(&error, bz);
      throw ParseError(path, 0, "bzip2 data is corrupt or truncated");
    }
    void* rest = nullptr;
    int rest_size = 0;
    BZ2_bzReadGetUnused(&error, bz, &rest, &rest_size);
    unused.assign(static_cast<const char*>(rest), static_cast<std::size_t>(rest_size));
    BZ2_bzReadClose(&error, bz);
    if (unused.empty()) {
      const int next = std::fgetc(file.get());
      if (next == EOF) break;
      std::ungetc(next, file.get());
    }
  }
  return out;
}

}  // namespace

std::string read_maybe_compressed(const std::string& path, std::size_t max_bytes) {
  if (path == "-") {
    const std::string& in = standard_input(max_bytes);
    if ((in.size() >= 2 && static_cast<unsigned char>(in[0]) == 0x1f && static_cast<unsigned char>(in[1]) == 0x8b) ||
        in.compare(0, 3, "BZh") == 0) {
      throw ParseError("standard input", 0, "compressed data on standard input: decompress it first (zcat, bzcat)");
    }
    return in;
  }
  char magic[3] = {0, 0, 0};
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ParseError(path, 0, std::string("cannot open file: ") + std::strerror(errno));
    in.read(magic, 3);
  }
  if (static_cast<unsigned char>(magic[0]) == 0x1f && static_cast<unsigned char>(magic[1]) == 0x8b) return gunzip(path, max_bytes);
  if (std::memcmp(magic, "BZh", 3) == 0) return bunzip2(path, max_bytes);
  std::string raw = read_raw(path);
  check_size(path, raw.size(), max_bytes);
  return raw;
}

}  // namespace cairn::io
