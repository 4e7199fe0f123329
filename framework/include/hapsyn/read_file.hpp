#pragma once
/// \file
/// Reading a whole input file safely: only regular files (a FIFO, a device such as /dev/zero or
/// a directory is refused before it is opened for reading, so nothing blocks or fills memory),
/// and only up to a stated size.
#include <cstddef>
#include <cstdint>
#include <string>

namespace hapsyn {

/// Returns the content of the regular file `path`.
/// \param path       the file
/// \param component  who reads it, the prefix of the error ("problem", "checkpoint", "human_arm")
/// \param what       what the file is, for the message ("problem file", "checkpoint", "cache")
/// \param max_bytes  the largest size accepted [bytes]
/// \throws Error `("<component>: cannot read <what> <path>: <reason>")` when it does not exist
///         or cannot be read; `Error("<component>: <what> <path> is not a regular file (a FIFO,
///         device or directory)")`; `Error("<component>: <what> <path> is <n> bytes, more than
///         the <max> this reader accepts")`.
std::string read_regular_file(const std::string& path, const std::string& component, const std::string& what,
                              std::uint64_t max_bytes);

/// True when `path` exists and is not a regular file (after following symbolic links): a FIFO,
/// a socket, a device or a directory. Cheap; for callers that want to refuse before opening.
bool exists_but_not_regular(const std::string& path);

/// The offset of the first byte of `text` that is not part of valid UTF-8 (overlong forms,
/// surrogates and code points above U+10FFFF are invalid), or std::string::npos. Readers check
/// the names they take from a file with it: a name that is not UTF-8 cannot be written into
/// result.json, so it is refused where it is read, naming the file and line.
std::size_t invalid_utf8_at(const std::string& text);

/// `text` as a message shows it whatever its bytes: in double quotes, printable ASCII as is,
/// every other byte as `\xHH`, at most 80 bytes ("..." after them).
std::string shown_bytes(const std::string& text);

}  // namespace hapsyn
