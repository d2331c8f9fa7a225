// SHA-256 of a file's bytes, as lower-case hex: the content hash a report
// records for its study file, checkable with `sha256sum`. OpenSSL's libcrypto
// (Debian libssl-dev) rather than a hand-written digest.
#pragma once

#include <string>

namespace penumbra {

// std::runtime_error when the file cannot be read.
std::string sha256_file_hex(const std::string& path);

}  // namespace penumbra
