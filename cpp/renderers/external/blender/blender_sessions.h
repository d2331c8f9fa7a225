// Blender processes kept running between renders (harness/blender_render.py
// --serve), so that Blender's start-up (about 1 s of a 1-4 s render) is paid
// once per process rather than per render. A study keeps one set for its run
// (RenderSettings::blender_sessions); blender_driver.cpp implements it.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace penumbra {

// A render takes an idle process that its own thread started, or starts one:
// a process ends with the thread that started it (util/process.h), so each
// worker thread has its own. Each job starts from Blender's factory
// settings, so its pixels do not depend on what the process rendered before
// (tested). A process that fails, times out or was stopped is ended; the
// next render starts a fresh one. Their logs live in a work folder inside
// `folder`, removed by the destructor, which also ends the processes.
class BlenderSessions {
 public:
  explicit BlenderSessions(std::string folder);
  ~BlenderSessions();
  BlenderSessions(const BlenderSessions&) = delete;
  BlenderSessions& operator=(const BlenderSessions&) = delete;

  struct Session;
  // An idle process of this executable and script, or a new one (started
  // lazily by its first render).
  std::unique_ptr<Session> acquire(const std::string& executable, const std::string& script);
  void release(std::unique_ptr<Session> session);
  // Processes started so far (a benchmark and the tests read it).
  int started() const;

 private:
  std::string folder_, work_;
  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<Session>> idle_;
  int started_ = 0, next_id_ = 0;
};

}  // namespace penumbra
