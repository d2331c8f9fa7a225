// The POV-Ray driver: exports the scene, runs POV-Ray, box-filters its
// supersampled image. In POV-Ray's part of the cache key (code_digest.h).
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "image/image.h"
#include "renderers/external/external.h"
#include "renderers/external/povray/povray.h"

namespace penumbra {

RendererRun render_povray(const Scene& scene, const RenderSettings& settings) {
  using namespace external;
  const RendererInfo& info = povray_entry().info;
  const PovrayExport job = export_povray(scene);
  const std::string exe = executable_for(info, settings);
  WorkDir work(settings.log_path, info);
  try {  // a full disk is this render's failure, not the study's
    write_povray_files(job, work.path.string());
  } catch (const std::exception& e) {
    throw RendererError(fmt::format("cannot write the POV-Ray job: {}", e.what()));
  }
  std::vector<std::string> argv{exe};
  for (std::string& a : job.arguments(kPovraySceneFile, "scene.exr", thread_count(settings)))
    argv.push_back(std::move(a));
  const ExternalRun ext = run_external(info, argv, work, "scene.exr", settings);
  const Image& big = ext.image;
  if (big.width != job.width * job.supersample_x || big.height != job.height * job.supersample_y)
    throw RendererError(fmt::format("povray wrote {}x{}, expected {}x{}", big.width, big.height,
                                    job.width * job.supersample_x, job.height * job.supersample_y));
  const Image colour = box_downsample(big, job.supersample_x, job.supersample_y);
  return with_geometry(info, colour, ext.seconds, scene, settings, work);
}

}  // namespace penumbra
