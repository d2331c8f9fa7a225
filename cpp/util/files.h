// Temporary files that say who made them, so that what a killed process left
// behind (kill -9, power loss) can be told from what a live one is writing,
// also when several machines share a folder.
#pragma once

#include <cstddef>
#include <string>

namespace penumbra {

// The whole file, as bytes; empty when it is missing or unreadable (for
// logs and stamps, whose absence the caller handles as "nothing there").
std::string read_file(const std::string& path);

// Why `path` cannot be read as an input file ("" when it is a regular file,
// after symbolic links): "no such file", "is a folder", "is a FIFO ...",
// "is a character device ..." (/dev/zero would be read forever), or the
// system's reason (a symbolic-link loop). Callers put it into their one line.
std::string input_file_problem(const std::string& path);

// This machine's host name, reduced to [A-Za-z0-9-] ("host" if none).
const std::string& host_tag();

// A hidden name in the folder of `path` for writing it: ".STEM.penumbra-tmp.HOST.PID.N.EXT"
// (the extension kept, since OpenImageIO picks the format from it). N counts
// within the process, so two threads never share a name.
std::string temporary_name(const std::string& path);

// The marker of work folders: ".penumbra-work.RENDERER.HOST.PID.XXXXXX".
std::string work_folder_pattern(const std::string& renderer);

// Removes, directly inside `folder`, temporary files and work folders made by
// processes of this host that no longer run. Returns how many entries went.
std::size_t remove_stale_temporaries(const std::string& folder);

}  // namespace penumbra
