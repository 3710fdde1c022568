// Files written whole or not at all (AtomicFileSet, WriteFileAtomically, WriteTextFileAtomically)
// and bounded reads of text inputs (ReadFileBounded): include/atmo/image.h. Apart from the image
// codecs (image_io.cc) so that builds without OpenEXR and libpng (web/) have them.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "atmo/error.h"
#include "atmo/image.h"
#include "atmo/interrupt.h"
#include "io/messages.h"

namespace atmo {

namespace fs = std::filesystem;


namespace {

// fsync of a file or folder by name; false (errno set) when it cannot be opened or synced.
bool SyncPath(const fs::path& path, bool directory) {
  const int fd = ::open(path.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  const int error = errno;
  ::close(fd);
  errno = error;
  return ok;
}

}  // namespace

// One staged file: its target (a symbolic link resolved), folder, the stat of what it replaces,
// and its temporary, registered for removal on SIGINT/SIGTERM.
struct AtomicFileSet::Staged {
  fs::path path;    // as given, for messages
  fs::path target;  // the final target of a symbolic link, else path
  fs::path dir;
  fs::path temporary;
  bool exists = false;
  struct stat existing {};
  int signal_slot = -1;

  void Discard() {
    std::error_code ignored;
    if (!temporary.empty()) fs::remove(temporary, ignored);
    ReleaseTemporaryFile(signal_slot);
    signal_slot = -1;
    temporary.clear();
  }
};

AtomicFileSet::AtomicFileSet() = default;

AtomicFileSet::~AtomicFileSet() {
  for (Staged& staged : staged_) staged.Discard();
}

void AtomicFileSet::Stage(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  if (committed_) throw Error(WriteError(path, "the file set was already committed"));
  if (path.empty()) throw Error("cannot write '': empty path");
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw Error(WriteError(path, "is a directory"));
  if (!path.has_filename()) throw Error(WriteError(path, "the path names no file"));

  Staged staged;
  staged.path = path;
  // A symbolic link is written through to its final target, so that the link stays a link (a
  // rename onto the link would replace it by a plain file). A dangling link is refused rather
  // than guessed at.
  staged.target = path;
  if (fs::is_symlink(fs::symlink_status(path, ec))) {
    staged.target = fs::canonical(path, ec);
    if (ec) throw Error(WriteError(path, "is a symbolic link to a missing file"));
  }
  // An existing target must be a regular file: rename would replace a device (as root,
  // `--out /dev/null` became a plain file), a FIFO or a socket by a plain file.
  staged.exists = ::stat(staged.target.c_str(), &staged.existing) == 0;
  if (staged.exists && S_ISDIR(staged.existing.st_mode)) throw Error(WriteError(path, "is a directory"));
  if (staged.exists && !S_ISREG(staged.existing.st_mode)) {
    throw Error(WriteError(path, "is not a regular file (a device, FIFO or socket); atmo writes only regular files"));
  }
  for (const Staged& other : staged_) {
    if (other.target == staged.target) throw Error(WriteError(path, "is staged twice"));
  }

  staged.dir = staged.target.has_parent_path() ? staged.target.parent_path() : fs::path(".");
  if (!fs::exists(staged.dir, ec)) {
    throw Error(WriteError(path, "directory '" + staged.dir.string() + "' does not exist"));
  }
  if (!fs::is_directory(staged.dir, ec)) {
    throw Error(WriteError(path, "'" + staged.dir.string() + "' is not a directory"));
  }
  if (::access(staged.dir.c_str(), W_OK | X_OK) != 0) {
    throw Error(WriteError(path, "directory '" + staged.dir.string() + "' is not writable"));
  }

  // Hidden, unique per process and call, in the same directory so that rename is atomic.
  static std::atomic<unsigned> counter{0};
  std::string temporary_name = ".";
  temporary_name += staged.target.filename().string();
  temporary_name += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1));
  staged.temporary = staged.dir / temporary_name;
  // SIGINT/SIGTERM remove it (include/atmo/interrupt.h) while it exists under this name.
  staged.signal_slot = RegisterTemporaryFile(staged.temporary.c_str());
  const auto fail = [&](const std::string& reason) {
    staged.Discard();
    return Error(WriteError(path, reason));
  };

  try {
    write(staged.temporary);
  } catch (const std::exception& e) {
    throw fail(e.what());
  } catch (...) {
    throw fail("unknown error");
  }
  if (!fs::is_regular_file(staged.temporary, ec)) throw fail("the writer produced no file");
  // A file replaced keeps its mode and its owner; the owner only where we may give it (root, or
  // our own file); otherwise nothing is replaced.
  if (staged.exists) {
    struct stat written {};
    if (::stat(staged.temporary.c_str(), &written) != 0 ||
        ::chmod(staged.temporary.c_str(), staged.existing.st_mode & 07777) != 0) {
      throw fail(std::string("cannot keep its mode: ") + std::strerror(errno));
    }
    if ((written.st_uid != staged.existing.st_uid || written.st_gid != staged.existing.st_gid) &&
        ::chown(staged.temporary.c_str(), staged.existing.st_uid, staged.existing.st_gid) != 0) {
      throw fail(std::string("cannot keep its owner: ") + std::strerror(errno));
    }
  }
  // The data reaches the disc before the name does.
  if (!SyncPath(staged.temporary, false)) throw fail(std::string("fsync failed: ") + std::strerror(errno));
  staged_.push_back(std::move(staged));
}

void AtomicFileSet::Commit() {
  if (committed_) return;
  committed_ = true;
  std::error_code ec;
  // A signal waits until every file is renamed (then removes nothing of the set and ends).
  const DeferInterrupts defer;
  for (Staged& staged : staged_) {
    fs::rename(staged.temporary, staged.target, ec);
    if (ec) {
      const std::string reason = ec.message();
      for (Staged& rest : staged_) {
        if (!rest.temporary.empty() && fs::exists(rest.temporary)) rest.Discard();
      }
      throw Error(WriteError(staged.path, reason));
    }
    ReleaseTemporaryFile(staged.signal_slot);
    staged.signal_slot = -1;
    staged.temporary.clear();
  }
  // The new names reach the disc before we report success.
  for (const Staged& staged : staged_) {
    if (!SyncPath(staged.dir, true)) {
      throw Error(WriteError(staged.path, std::string("fsync of the folder failed: ") + std::strerror(errno)));
    }
  }
}

void WriteTextFileAtomically(const fs::path& path, const std::string& text) {
  WriteFileAtomically(path, [&](const fs::path& temporary) {
    std::ofstream out(temporary, std::ios::binary);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    out.close();
    if (!out) throw Error("write failed");
  });
}

void WriteFileAtomically(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  AtomicFileSet set;
  set.Stage(path, write);
  set.Commit();
}

std::string ReadFileBounded(const fs::path& path, const std::string& what, std::uintmax_t max_bytes) {
  const auto fail = [&](const std::string& reason) -> Error {
    return Error("cannot read " + what + "'" + OneLine(path.string()) + "': " + reason);
  };
  // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw fail(std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int error = errno;
    ::close(fd);
    throw fail(std::strerror(error));
  }
  if (S_ISDIR(st.st_mode)) {
    ::close(fd);
    throw fail("is a directory");
  }
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    throw fail("is not a regular file (a device, FIFO or socket)");
  }
  const auto too_large = [&] {
    const std::string limit = max_bytes % (std::uintmax_t{1} << 20) == 0 && max_bytes > 0
                                  ? std::to_string(max_bytes >> 20) + " MiB"
                                  : std::to_string(max_bytes) + " bytes";
    return fail("larger than the " + limit + " allowed");
  };
  if (static_cast<std::uintmax_t>(st.st_size) > max_bytes) {
    ::close(fd);
    throw too_large();
  }
  std::string text;
  char buffer[65536];
  while (true) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      ::close(fd);
      throw fail(std::strerror(error));
    }
    if (n == 0) break;
    text.append(buffer, static_cast<std::size_t>(n));
    if (text.size() > max_bytes) {  // a file that grows while we read it
      ::close(fd);
      throw too_large();
    }
  }
  ::close(fd);
  return text;
}
}  // namespace atmo
