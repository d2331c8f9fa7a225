// The sentences a report prints about its rankings, generated from the
// numbers in study/ranking.h alone (every number with its interval and what
// it was compared against).
#pragma once

#include <string>
#include <vector>

#include "study/ranking.h"

namespace penumbra {

// One ranking's findings: the leading group, each leader against raw bump,
// grazing-view penalties, rejected methods.
std::vector<std::string> finding_sentences(const RankingStatistics& s);

// The report's lead, 3 to 6 sentences: the leading group, methods worse than
// raw bump, and where a method's effect depends on an axis (helps at one
// level, hurts or ties at another).
std::vector<std::string> lead_sentences(const StudyStatistics& s);

// Where the mean absolute terminator RMSE (study/compare.h rank_bump) puts a
// method on the other side of raw bump than the primary metric, and why.
std::vector<std::string> quantity_notes(const StudyStatistics& s, const Plan& plan,
                                        const std::vector<ComparisonRow>& rows);

}  // namespace penumbra
