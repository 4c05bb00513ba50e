// Format dispatch, file reading, and atomic file writing.

#include "shatter/kernel/io.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <functional>
#include <initializer_list>
#include <memory>
#include <string>
#include <system_error>
#include <utility>

#include "io_internal.hpp"
#include "shatter/kernel/atomic_file.hpp"
#include "shatter/kernel/error.hpp"

namespace shatter {

namespace {

std::string lower_case(std::string_view text) {
  std::string lowered(text);
  for (char& c : lowered) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return lowered;
}

/// `text` with every byte outside printable ASCII written as \xNN.
std::string printable(std::string_view text) {
  std::string escaped;
  escaped.reserve(text.size());
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f) {
      escaped += c;
      continue;
    }
    constexpr char hex[] = "0123456789abcdef";
    escaped += "\\x";
    escaped += hex[byte >> 4];
    escaped += hex[byte & 0xf];
  }
  return escaped;
}

std::string describe_errno(const std::filesystem::path& path, const char* action, int error) {
  return "cannot " + std::string(action) + " " + path.string() + ": " + std::strerror(error);
}

std::string read_file(const std::filesystem::path& path) {
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw IoError(describe_errno(path, "open", errno));
  std::string bytes;
  // A regular file is read in one call into a buffer of its size: appending
  // 64 KiB chunks to a growing string copied a large mesh file about twice over
  // and cost a third of reading it. The chunked loop then only meets what a file
  // that grew meanwhile, or a pipe, still holds.
  struct stat status {};
  if (::fstat(::fileno(file.get()), &status) == 0 && S_ISREG(status.st_mode) && status.st_size > 0) {
    bytes.resize(static_cast<std::size_t>(status.st_size));
    bytes.resize(std::fread(bytes.data(), 1, bytes.size(), file.get()));
  }
  char buffer[1 << 16];
  while (!std::ferror(file.get())) {
    const std::size_t read = std::fread(buffer, 1, sizeof buffer, file.get());
    bytes.append(buffer, read);
    if (read < sizeof buffer) break;
  }
  // A directory opens but fails to read (EISDIR).
  if (std::ferror(file.get())) throw IoError(describe_errno(path, "read", errno));
  return bytes;
}

/// A new file open for writing, closed (and, unless released, removed) on
/// destruction.
class NewFile {
 public:
  /// Creates `path`, which must not exist; `error` gets errno on failure.
  NewFile(std::filesystem::path path, int& error)
      : path_(std::move(path)), descriptor_(::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666)) {
    error = descriptor_ < 0 ? errno : 0;
  }
  ~NewFile() {
    if (descriptor_ >= 0) ::close(descriptor_);
    if (!kept_ && created_) ::unlink(path_.c_str());
  }
  NewFile(const NewFile&) = delete;
  NewFile& operator=(const NewFile&) = delete;

  /// Appends all of `bytes`; returns 0 or errno.
  int write(std::string_view bytes) {
    while (!bytes.empty()) {
      const ssize_t written = ::write(descriptor_, bytes.data(), bytes.size());
      if (written < 0 && errno == EINTR) continue;
      if (written < 0) return errno;
      bytes.remove_prefix(static_cast<std::size_t>(written));
    }
    return 0;
  }
  /// Replaces bytes from `offset` on with all of `bytes`; returns 0 or errno.
  int write_at(std::uint64_t offset, std::string_view bytes) {
    while (!bytes.empty()) {
      const ssize_t written = ::pwrite(descriptor_, bytes.data(), bytes.size(), static_cast<off_t>(offset));
      if (written < 0 && errno == EINTR) continue;
      if (written < 0) return errno;
      bytes.remove_prefix(static_cast<std::size_t>(written));
      offset += static_cast<std::uint64_t>(written);
    }
    return 0;
  }
  /// Closes the file; returns 0 or errno (close() can report a deferred write
  /// failure: NFS, a full disk).
  int close() {
    const int result = ::close(descriptor_);
    descriptor_ = -1;
    return result == 0 ? 0 : errno;
  }
  /// The file stays when this is destroyed.
  void keep() { kept_ = true; }

 private:
  std::filesystem::path path_;
  int descriptor_;
  bool created_ = descriptor_ >= 0;
  bool kept_ = false;
};

}  // namespace

std::optional<MeshFormat> format_from_extension(const std::filesystem::path& path) {
  const std::string extension = path.extension().string();
  if (extension.empty()) return std::nullopt;
  return parse_mesh_format(std::string_view(extension).substr(1));
}

std::optional<MeshFormat> parse_mesh_format(std::string_view name) {
  const std::string lowered = lower_case(name);
  for (const MeshFormat format : {MeshFormat::off, MeshFormat::obj, MeshFormat::ply, MeshFormat::stl}) {
    if (lowered == format_name(format)) return format;
  }
  return std::nullopt;
}

std::string_view format_name(MeshFormat format) {
  switch (format) {
    case MeshFormat::off: return "off";
    case MeshFormat::obj: return "obj";
    case MeshFormat::ply: return "ply";
    case MeshFormat::stl: return "stl";
  }
  return "unknown";
}

Mesh read_mesh(const std::filesystem::path& path, std::vector<std::string>* warnings) {
  const std::optional<MeshFormat> format = format_from_extension(path);
  if (!format) {
    throw InvalidMeshError("unknown mesh format of " + path.string() + " (expected .off, .obj, .ply or .stl)");
  }
  const std::string bytes = read_file(path);
  try {
    return read_mesh_from_bytes(bytes, *format, warnings);
  } catch (const InvalidMeshError& error) {
    throw InvalidMeshError(path.string() + ": " + error.what());
  }
}

Mesh read_mesh_from_bytes(std::string_view bytes, MeshFormat format, std::vector<std::string>* warnings) {
  // Said once here, an empty file is refused as empty: each reader alone would
  // complain about its missing first keyword, a different message per format.
  if (bytes.empty()) throw InvalidMeshError("empty file (0 bytes)");
  if (bytes.find_first_not_of(" \t\r\n\v\f") == std::string_view::npos) {
    throw InvalidMeshError("blank file: " + std::to_string(bytes.size()) + " bytes of whitespace and nothing else");
  }
  // The warnings reach the caller only with the mesh: a refused file has no
  // liberties taken to report.
  std::vector<std::string> taken;
  const auto with_warnings = [&](Mesh mesh) {
    if (warnings) {
      for (std::string& line : taken) warnings->push_back(printable(line));
    }
    return mesh;
  };
  try {
    switch (format) {
      case MeshFormat::off: return with_warnings(io_detail::read_off(bytes, taken));
      case MeshFormat::obj: return with_warnings(io_detail::read_obj(bytes, taken));
      case MeshFormat::ply: return with_warnings(io_detail::read_ply(bytes, taken));
      case MeshFormat::stl: return with_warnings(io_detail::read_stl(bytes, taken));
    }
  } catch (const InvalidMeshError& error) {
    // Messages quote tokens from the file, which may be binary garbage; the
    // one-line error the CLI prints must stay printable text.
    throw InvalidMeshError(printable(error.what()));
  }
  throw InvalidMeshError("unknown mesh format");
}

std::string write_mesh_to_bytes(const Mesh& mesh, MeshFormat format) {
  switch (format) {
    case MeshFormat::off: return io_detail::write_off(mesh);
    case MeshFormat::obj: return io_detail::write_obj(mesh);
    case MeshFormat::ply: return io_detail::write_ply(mesh);
    case MeshFormat::stl: return io_detail::write_stl(mesh);
  }
  throw InvalidMeshError("unknown mesh format");
}

void write_mesh(const Mesh& mesh, const std::filesystem::path& path, MeshFormat format) {
  write_file_atomically(path, write_mesh_to_bytes(mesh, format));
}

void write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
  write_file_atomically_in_pieces(path, [&](const ByteSink& sink) { sink(bytes); });
}

void write_file_atomically_in_pieces(const std::filesystem::path& path, const std::function<void(const ByteSink&)>& produce) {
  write_file_atomically_rewritable(path, [&](const RewritableSink& sink) { produce(sink.append); });
}

void write_file_atomically_rewritable(const std::filesystem::path& path, const std::function<void(const RewritableSink&)>& produce) {
  // The temporary sits beside the target so the rename stays on one file system
  // (and so is atomic); pid and counter keep concurrent writers apart.
  static std::atomic<unsigned long> counter{0};
  std::filesystem::path temporary = path;
  temporary += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);

  int error = 0;
  NewFile file(temporary, error);
  if (error != 0) throw IoError(describe_errno(path, "write", error));
  const RewritableSink sink{
      [&](std::string_view piece) {
        if (const int write_error = file.write(piece); write_error != 0) throw IoError(describe_errno(path, "write", write_error));
      },
      [&](std::uint64_t offset, std::string_view bytes) {
        if (const int write_error = file.write_at(offset, bytes); write_error != 0) {
          throw IoError(describe_errno(path, "write", write_error));
        }
      }};
  produce(sink);
  if (const int close_error = file.close(); close_error != 0) throw IoError(describe_errno(path, "write", close_error));
  std::error_code rename_error;
  std::filesystem::rename(temporary, path, rename_error);
  if (rename_error) throw IoError("cannot write " + path.string() + ": " + rename_error.message());
  file.keep();
}

}  // namespace shatter
