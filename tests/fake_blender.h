// Stand-ins for Blender in tests: shell scripts that speak the protocol of
// harness/blender_render.py --serve (one JSON request per stdin line, the
// answer an image at the request's "output") and answer --version.
#pragma once

#include <string>

namespace penumbra {

// A fake's answer with `image` as the real script gives it: written beside
// and renamed into place, since Penumbra reads render.exr as soon as it
// appears (a plain cp was read half-written on a loaded machine).
inline std::string fake_blender_answer(const std::string& image) {
  return "cp '" + image + "' render.exr.part && mv render.exr.part render.exr";
}

// The text of a fake Blender. For each request it changes into the folder of
// the request's output (the render's work folder, where Penumbra expects
// render.exr) and runs `body` there: `exit 1` ends the whole fake, as a crash
// of a serving Blender would. `version_body` runs before --version answers.
inline std::string fake_blender_text(const std::string& body,
                                     const std::string& version_body = "") {
  return "#!/bin/sh\ncase \"$*\" in *--version*) " +
         (version_body.empty() ? std::string() : version_body + ";") +
         " echo 'Blender 3.4.1'; exit 0;; esac\n"
         "while IFS= read -r request; do\n"
         "  output=$(printf '%s\\n' \"$request\" | sed -n "
         "'s/.*\"output\":\"\\([^\"]*\\)\".*/\\1/p')\n"
         "  cd \"$(dirname \"$output\")\" || exit 3\n" +
         body + "\ndone\n";
}

}  // namespace penumbra
