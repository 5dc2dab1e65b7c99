#include "cairn/io/compressed_file.hpp"

#include <bzlib.h>
#include <lzma.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <system_error>

#include "cairn/io/input_file.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::io {
namespace {

// Stops as soon as the file holds more than `max_bytes` (a device or a huge file is never read
// whole before the limit is checked).
std::string read_raw(const std::string& path, std::size_t max_bytes) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw ParseError(path, 0, std::string("cannot open file: ") + std::strerror(errno));
  std::string out;
  char buffer[1 << 16];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, file.get())) > 0) {
    out.append(buffer, n);
    if (out.size() > max_bytes) throw ParseError(path, 0, "is larger than " + std::to_string(max_bytes) + " bytes: refusing to read it");
  }
  if (std::ferror(file.get())) throw ParseError(path, 0, "read error");
  return out;
}

void check_size(const std::string& path, std::size_t size, std::size_t max_bytes) {
  if (size > max_bytes) {
    throw ParseError(path, 0, "decompressed data exceeds " + std::to_string(max_bytes) + " bytes: refusing to read it");
  }
}

// Room for the decompressed text, guessed from the file's size (text compresses 4-10 times):
// without it the string doubles its way up, copying and touching fresh memory at every step.
// Only what is written is touched, so a generous guess costs address space, not memory.
void reserve_decompressed(std::string& out, const std::string& path, std::size_t max_bytes) {
  std::error_code error;
  const auto compressed = std::filesystem::file_size(path, error);
  if (error) return;
  out.reserve(static_cast<std::size_t>(std::min<std::uintmax_t>(max_bytes, compressed * 16)));
}

std::string gunzip(const std::string& path, std::size_t max_bytes) {
  gzFile file = gzopen(path.c_str(), "rb");
  if (file == nullptr) throw ParseError(path, 0, std::string("cannot open gzip file: ") + std::strerror(errno));
  std::string out;
  reserve_decompressed(out, path, max_bytes);
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
  reserve_decompressed(out, path, max_bytes);
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

/// xz (LZMA2 in the .xz container, as `xz` writes it), decoded with liblzma. Concatenated
/// streams are read one after the other, as `xz -d` does; the integrity check (CRC64 by
/// default) is verified by the decoder.
std::string unxz(const std::string& path, std::size_t max_bytes) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw ParseError(path, 0, std::string("cannot open xz file: ") + std::strerror(errno));
  lzma_stream stream = LZMA_STREAM_INIT;
  if (lzma_stream_decoder(&stream, UINT64_MAX, LZMA_CONCATENATED) != LZMA_OK) {
    throw ParseError(path, 0, "cannot start the xz decoder (out of memory?)");
  }
  std::unique_ptr<lzma_stream, void (*)(lzma_stream*)> guard(&stream, &lzma_end);
  std::string out;
  reserve_decompressed(out, path, max_bytes);
  std::uint8_t input[1 << 16];
  std::uint8_t buffer[1 << 16];
  lzma_action action = LZMA_RUN;
  while (true) {
    if (stream.avail_in == 0 && action == LZMA_RUN) {
      stream.next_in = input;
      stream.avail_in = std::fread(input, 1, sizeof input, file.get());
      if (std::ferror(file.get())) throw ParseError(path, 0, "read error");
      // LZMA_FINISH at the end of the input: the decoder then reports a stream that stops
      // before its footer (LZMA_BUF_ERROR) instead of waiting for more bytes.
      if (std::feof(file.get())) action = LZMA_FINISH;
    }
    stream.next_out = buffer;
    stream.avail_out = sizeof buffer;
    const lzma_ret status = lzma_code(&stream, action);
    out.append(reinterpret_cast<const char*>(buffer), sizeof buffer - stream.avail_out);
    check_size(path, out.size(), max_bytes);
    if (status == LZMA_STREAM_END) break;
    if (status == LZMA_OK) continue;
    switch (status) {
      case LZMA_BUF_ERROR:
        throw ParseError(path, 0, "xz data is truncated (the stream ends before its footer)");
      case LZMA_MEM_ERROR:
        throw ParseError(path, 0, "out of memory while decompressing xz data");
      case LZMA_FORMAT_ERROR:
        throw ParseError(path, 0, "xz data is corrupt: not in the .xz format");
      case LZMA_OPTIONS_ERROR:
        throw ParseError(path, 0, "xz data uses options this liblzma does not support");
      case LZMA_DATA_ERROR:
        throw ParseError(path, 0, "xz data is corrupt (bad compressed data or trailing garbage)");
      default:
        throw ParseError(path, 0, "xz data is corrupt (liblzma error " + std::to_string(static_cast<int>(status)) + ")");
    }
  }
  return out;
}

bool is_xz(const char* bytes, std::size_t size) {
  static constexpr unsigned char kMagic[6] = {0xfd, 0x37, 0x7a, 0x58, 0x5a, 0x00};
  return size >= 6 && std::memcmp(bytes, kMagic, 6) == 0;
}

}  // namespace

std::string read_maybe_compressed(const std::string& path, std::size_t max_bytes) {
  if (path == "-") {
    const std::string& in = standard_input(max_bytes);
    if ((in.size() >= 2 && static_cast<unsigned char>(in[0]) == 0x1f && static_cast<unsigned char>(in[1]) == 0x8b) ||
        in.compare(0, 3, "BZh") == 0 || is_xz(in.data(), in.size())) {
      throw ParseError("standard input", 0, "compressed data on standard input: decompress it first (zcat, bzcat, xzcat)");
    }
    return in;
  }
  check_input_file(path);
  char magic[6] = {0, 0, 0, 0, 0, 0};
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ParseError(path, 0, std::string("cannot open file: ") + std::strerror(errno));
    in.read(magic, 6);
  }
  if (static_cast<unsigned char>(magic[0]) == 0x1f && static_cast<unsigned char>(magic[1]) == 0x8b) return gunzip(path, max_bytes);
  if (std::memcmp(magic, "BZh", 3) == 0) return bunzip2(path, max_bytes);
  if (is_xz(magic, sizeof magic)) return unxz(path, max_bytes);
  return read_raw(path, max_bytes);
}

}  // namespace cairn::io
