#pragma once
// Maps an HTTP request target to a file under the web root, refusing anything that could leave
// it ("..", encoded or not, backslashes, NUL, symlinks pointing out), and names content types.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace skinstream::server {

// The file to serve for `target` ("/" -> index.html), or nullopt when the target is unsafe or
// names no regular file inside `root`.
std::optional<std::filesystem::path> resolve_static_file(const std::filesystem::path& root, std::string_view target);

// Content type by extension (.html .js .css .png .json .wasm ...; application/octet-stream otherwise).
std::string_view content_type_for(const std::filesystem::path& file);

}  // namespace skinstream::server
