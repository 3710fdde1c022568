#include "gl/timer_queries.h"

#include <algorithm>
#include <cstdint>

#include <epoxy/gl.h>

namespace atmo::gl {
namespace {

thread_local TimerQueries* t_current = nullptr;

}  // namespace

std::shared_ptr<TimerQueries> CurrentTimerQueries() {
  return t_current != nullptr ? t_current->shared_from_this() : nullptr;
}

void SetCurrentTimerQueries(TimerQueries* queries) { t_current = queries; }

std::shared_ptr<GpuTimeRecord> TimerQueries::Begin() {
  Prune();
  auto record = std::make_shared<GpuTimeRecord>();
  GLuint names[2] = {0, 0};
  glGenQueries(2, names);
  record->begin = names[0];
  record->end = names[1];
  glQueryCounter(record->begin, GL_TIMESTAMP);
  records_.push_back(record);
  return record;
}

void TimerQueries::End(GpuTimeRecord& record) {
  if (record.end != 0) glQueryCounter(record.end, GL_TIMESTAMP);
}

void TimerQueries::Finish(GpuTimeRecord& record) {
  GLuint64 begin_ns = 0;
  GLuint64 end_ns = 0;
  glGetQueryObjectui64v(record.begin, GL_QUERY_RESULT, &begin_ns);
  glGetQueryObjectui64v(record.end, GL_QUERY_RESULT, &end_ns);
  record.ms = end_ns > begin_ns ? static_cast<double>(end_ns - begin_ns) * 1e-6 : 0.0;
  record.done = true;
  const GLuint names[2] = {record.begin, record.end};
  glDeleteQueries(2, names);
  record.begin = 0;
  record.end = 0;
}

std::optional<double> TimerQueries::Read(GpuTimeRecord& record, bool wait) {
  if (record.done) return record.ms;
  if (!live_ || t_current != this) return std::nullopt;  // its context is not current here
  if (!wait) {
    GLint available = 0;
    glGetQueryObjectiv(record.end, GL_QUERY_RESULT_AVAILABLE, &available);
    if (available == 0) return std::nullopt;
  }
  Finish(record);
  return record.ms;
}

void TimerQueries::Prune() {
  // Read records leave; unread ones that only this list still holds are deleted unread.
  std::erase_if(records_, [](const std::shared_ptr<GpuTimeRecord>& record) {
    if (record->done) return true;
    if (record.use_count() > 1) return false;
    const GLuint names[2] = {record->begin, record->end};
    glDeleteQueries(2, names);
    return true;
  });
}

void TimerQueries::Drain() {
  if (!live_) return;
  Prune();
  for (const std::shared_ptr<GpuTimeRecord>& record : records_) {
    if (!record->done) Finish(*record);
  }
  records_.clear();
  live_ = false;
}

std::size_t TimerQueries::outstanding() const {
  return static_cast<std::size_t>(
      std::count_if(records_.begin(), records_.end(),
                    [](const auto& record) { return !record->done && record.use_count() > 1; }));
}

}  // namespace atmo::gl
