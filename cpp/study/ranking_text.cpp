#include "study/ranking_text.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include <fmt/format.h>

namespace penumbra {
namespace {

std::string percent(double fraction) {
  return fmt::format("{:.0f} %", 100.0 * fraction);
}

std::string percent_interval(const Interval& i) {
  return fmt::format("[{:.0f}, {:.0f}]", 100.0 * i.low, 100.0 * i.high);
}

// "86 % [82, 91]": a combined error as a share of raw bump's, with its interval.
std::string share(const MethodStatistics& m) {
  return percent(m.combined) + " " + percent_interval(m.combined_interval);
}

// A method's label, marked when the literature rejects it.
std::string named(const std::string& method, const std::string& rejected) {
  return rejected.empty() ? method : method + " [rejected in the literature]";
}

std::string p_text(double p) {
  return p < 0.001 ? std::string("p < 0.001") : fmt::format("p = {:.2g}", p);
}

// How a ranking's intervals are described: simultaneous 95 % over its
// comparisons (study/ranking.h).
std::string interval_kind(double confidence) {
  return fmt::format("simultaneous 95 % intervals, each at {:.2f} %", 100.0 * confidence);
}

std::string list_text(const std::vector<std::string>& items, const char* separator = ", ") {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i)
    out += (i == 0 ? "" : i + 1 == items.size() ? " and " : separator) + items[i];
  return out;
}

// "M lowers (raises) the terminator error of raw bump by X % [a, b]; better in
// W of N variants".
std::string versus_none(const MethodStatistics& m, double confidence) {
  const bool lowers = m.terminator_improvement >= 0.0;
  const Interval& i = m.terminator_interval;
  return fmt::format(
      "{} {} the terminator-region profile RMSE of raw bump by {} {} ({}), better in {} of {} "
      "variants{}.",
      named(m.method, m.rejected), lowers ? "lowers" : "raises",
      percent(std::abs(m.terminator_improvement)),
      percent_interval(lowers ? i : Interval{-i.high, -i.low}), interval_kind(confidence),
      m.terminator.a_better, m.terminator.n,
      i.contains(0.0) ? "; its interval contains 0: a tie" : "");
}

// Which methods are darker than the truth where the viewer looks edge-on.
std::string darker_at_grazing_views(const RankingStatistics& s) {
  std::string list;
  for (const MethodStatistics& m : s.methods)
    if (m.view_darker > 0)
      list += fmt::format("{}{} in {} of {} variants (mean signed error there {:+.2f} %)",
                          list.empty() ? "" : "; ", named(m.method, m.rejected), m.view_darker,
                          m.variants, 100.0 * m.view_darker_mean);
  if (list.empty()) return "";
  const MethodStatistics* none = s.find("none");
  return fmt::format(
      "Darker than the displacement ground truth at grazing views (view angle 60-75 deg, lit "
      "head-on; signed errors in % of albedo*E/pi), where raw bump is {:+.2f} % on average: {}.",
      100.0 * (none ? none->view_bias : std::numeric_limits<double>::quiet_NaN()), list);
}

// "M adds error at grazing views: ...", for a method whose grazing-view
// error is above raw bump's by an interval that excludes 0.
std::string worse_view(const MethodStatistics& m) {
  return fmt::format(
      "{} adds error where the viewer looks at grazing angles: its grazing-view RMSE is {:+.2f} % "
      "[{:+.2f}, {:+.2f}] of albedo*E/pi above raw bump's (worse in {} of {} variants); its "
      "mean signed error there is {:+.2f} % [{:+.2f}, {:+.2f}] ({} than the ground truth){}.",
      named(m.method, m.rejected), 100.0 * m.view.mean_difference, 100.0 * m.view.interval.low,
      100.0 * m.view.interval.high, m.view.b_better, m.view.n, 100.0 * m.view_bias,
      100.0 * m.view_bias_interval.low, 100.0 * m.view_bias_interval.high,
      m.view_bias < 0.0 ? "darker" : "brighter", m.rejected.empty() ? "" : " (" + m.rejected + ")");
}

// The members of the leader's group, the leader left out.
std::vector<std::string> first_group(const RankingStatistics& s) {
  std::vector<std::string> out;
  for (const MethodStatistics& m : s.methods)
    if (m.rank == 1 && m.method != s.methods.front().method)
      out.push_back(named(m.method, m.rejected));
  return out;
}

std::string leader_sentence(const RankingStatistics& s) {
  const MethodStatistics& best = s.methods.front();
  const std::vector<std::string> group = first_group(s);
  int groups = 0;
  for (const MethodStatistics& m : s.methods) groups = std::max(groups, m.rank);
  return fmt::format(
      "Closest to the displacement ground truth over {} variants: {} (combined error {} of raw "
      "bump's, {}){}.",
      s.variants, named(best.method, best.rejected), share(best), interval_kind(s.confidence),
      group.empty() ? fmt::format("; alone in rank group 1 of {}", groups)
                    : fmt::format("; rank group 1 of {} also holds {}, not separated from it",
                                  groups, list_text(group)));
}

}  // namespace

std::vector<std::string> finding_sentences(const RankingStatistics& s) {
  std::vector<std::string> out;
  if (s.methods.empty()) return out;
  out.push_back(leader_sentence(s));
  for (const MethodStatistics& m : s.methods)
    if (m.method != "none" && m.rank == 1) out.push_back(versus_none(m, s.confidence));
  for (const MethodStatistics& m : s.methods)
    if (m.rank == 1 && m.method != m.group_leader && m.versus_leader.n > 0)
      out.push_back(fmt::format(
          "{} and {} are tied: the mean paired difference of their combined errors is {:+.1f} "
          "percentage points of raw bump's [{:+.1f}, {:+.1f}], an interval that contains 0.",
          m.group_leader, m.method, 100.0 * m.versus_leader.mean_difference,
          100.0 * m.versus_leader.interval.low, 100.0 * m.versus_leader.interval.high));
  for (const MethodStatistics& m : s.methods)
    if (m.view.n > 0 && m.view.interval.low > 0.0) out.push_back(worse_view(m));
  if (std::string darker = darker_at_grazing_views(s); !darker.empty())
    out.push_back(std::move(darker));
  for (const MethodStatistics& m : s.methods)
    if (!m.rejected.empty() && m.rank == 1)
      out.push_back(fmt::format("{} is {}; it is ranked for comparison, not recommended.", m.method,
                                m.rejected));
  return out;
}

namespace {

// "amplitude A" from "amplitude A (scene units)".
std::string short_label(const AxisStatistics& a) {
  const std::string l = a.label.substr(0, a.label.find(" ("));
  return l.empty() ? a.pointer : l;
}

// "at amplitude A = 0.02", "for Lambert".
std::string at_level(const AxisStatistics& a, const LevelRanking& l) {
  return a.numeric ? fmt::format("at {} = {}", short_label(a), l.value_label)
                   : fmt::format("for {}", l.value_label);
}

enum class Verdict { kHelps, kTie, kHurts };

Verdict verdict(const MethodStatistics& m) {
  if (m.combined_interval.high < 1.0) return Verdict::kHelps;
  return m.combined_interval.low > 1.0 ? Verdict::kHurts : Verdict::kTie;
}

// The levels where method m does best and worst (by mean C).
std::pair<const LevelRanking*, const LevelRanking*> extreme_levels(const AxisStatistics& a,
                                                                   const std::string& m) {
  const LevelRanking *best = nullptr, *worst = nullptr;
  for (const LevelRanking& l : a.levels) {
    const MethodStatistics* s = l.ranking.find(m);
    if (!s || !std::isfinite(s->combined)) continue;
    if (!best || s->combined < best->ranking.find(m)->combined) best = &l;
    if (!worst || s->combined > worst->ranking.find(m)->combined) worst = &l;
  }
  return {best, worst};
}

// One method's strongest dependence on an axis, as a sentence.
std::string dependence_sentence(const StudyStatistics& s, const AxisStatistics& a,
                                const Interaction& i) {
  const auto [best, worst] = extreme_levels(a, i.method);
  const MethodStatistics& b = *best->ranking.find(i.method);
  const MethodStatistics& w = *worst->ranking.find(i.method);
  const MethodStatistics& all = *s.overall.find(i.method);
  const std::string test = fmt::format("interaction {}, Holm-adjusted over {} tests",
                                       p_text(i.p_holm), s.by_axis.size() * a.interactions.size());
  if (verdict(b) == Verdict::kHelps && verdict(w) == Verdict::kHurts)
    return fmt::format(
        "{} helps {} ({} of raw bump's error) and hurts {} ({}): its effect depends on the {} "
        "({}); over all variants it is {}, rank group {}.",
        i.method, at_level(a, *best), share(b), at_level(a, *worst), share(w), short_label(a), test,
        share(all), all.rank);
  const char* words[] = {"helps", "ties with raw bump", "hurts"};
  return fmt::format(
      "{}'s effect depends on the {} ({}): {} of raw bump's error {} ({}) against {} {} ({}).",
      i.method, short_label(a), test, share(b), at_level(a, *best),
      words[static_cast<int>(verdict(b))], share(w), at_level(a, *worst),
      words[static_cast<int>(verdict(w))]);
}

// The swing of method m's C over an axis's levels (worst minus best level).
double swing(const AxisStatistics& a, const std::string& m) {
  const auto [best, worst] = extreme_levels(a, m);
  return best ? worst->ranking.find(m)->combined - best->ranking.find(m)->combined : 0.0;
}

bool flips(const AxisStatistics& a, const std::string& m) {
  const auto [best, worst] = extreme_levels(a, m);
  return best && verdict(*best->ranking.find(m)) == Verdict::kHelps &&
         verdict(*worst->ranking.find(m)) == Verdict::kHurts;
}

using Dependence = std::pair<const AxisStatistics*, const Interaction*>;

// Each method's most significant dependence (smallest p, then the largest
// swing), those that help at one level and hurt at another first, the
// largest swing first.
std::vector<Dependence> dependences(const StudyStatistics& s) {
  std::map<std::string, Dependence> strongest;
  for (const AxisStatistics& a : s.by_axis)
    for (const Interaction& i : a.interactions) {
      if (!i.depends) continue;
      const auto it = strongest.find(i.method);
      if (it == strongest.end() || i.test.p < it->second.second->test.p ||
          (i.test.p == it->second.second->test.p &&
           swing(a, i.method) > swing(*it->second.first, i.method)))
        strongest[i.method] = {&a, &i};
    }
  std::vector<Dependence> out;
  for (const auto& [m, d] : strongest) out.push_back(d);
  std::stable_sort(out.begin(), out.end(), [](const Dependence& x, const Dependence& y) {
    const bool fx = flips(*x.first, x.second->method), fy = flips(*y.first, y.second->method);
    if (fx != fy) return fx;
    return swing(*x.first, x.second->method) > swing(*y.first, y.second->method);
  });
  return out;
}

// Where the leading group's methods help and where they do not, for the
// axis that moves them most.
std::string leaders_sentence(const StudyStatistics& s) {
  const AxisStatistics* axis = nullptr;
  double largest = 0.0;
  std::vector<std::string> leaders;
  for (const MethodStatistics& m : s.overall.methods)
    if (m.rank == 1 && m.method != "none") leaders.push_back(m.method);
  for (const AxisStatistics& a : s.by_axis)
    for (const Interaction& i : a.interactions)
      if (i.depends && std::find(leaders.begin(), leaders.end(), i.method) != leaders.end() &&
          swing(a, i.method) > largest)
        axis = &a, largest = swing(a, i.method);
  if (!axis) return "";
  const char* words[] = {"helps", "a tie", "hurts"};
  std::vector<std::string> clauses;
  for (const std::string& m : leaders) {
    const auto it = std::find_if(axis->interactions.begin(), axis->interactions.end(),
                                 [&](const Interaction& i) { return i.method == m; });
    if (it == axis->interactions.end() || !it->depends || clauses.size() == 3) continue;
    const auto [best, worst] = extreme_levels(*axis, m);
    const MethodStatistics &b = *best->ranking.find(m), &w = *worst->ranking.find(m);
    clauses.push_back(fmt::format("{} {} {} ({}), {} {} ({})", m, share(b), at_level(*axis, *best),
                                  words[static_cast<int>(verdict(b))], share(w),
                                  at_level(*axis, *worst), words[static_cast<int>(verdict(w))]));
  }
  return fmt::format(
      "The leading group's benefit depends on the {} (share of raw bump's combined error): {}.",
      short_label(*axis), list_text(clauses, "; "));
}

std::string worse_sentence(const RankingStatistics& s) {
  std::vector<std::string> worse;
  for (const MethodStatistics& m : s.methods)
    if (verdict(m) == Verdict::kHurts) worse.push_back(m.method + " (" + share(m) + ")");
  if (worse.empty())
    return "No method's combined error is above raw bump's over all variants by its interval.";
  return fmt::format("{} {} worse than raw bump over all variants: {}.", worse.size(),
                     worse.size() == 1 ? "method is" : "methods are", list_text(worse));
}

// Whether the leading method changes with an axis's level.
std::string leader_change_sentence(const StudyStatistics& s) {
  for (const AxisStatistics& a : s.by_axis) {
    std::vector<std::string> parts;
    std::string first;
    bool changes = false;
    for (const LevelRanking& l : a.levels) {
      if (l.ranking.methods.empty()) continue;
      const MethodStatistics& lead = l.ranking.methods.front();
      changes |= !first.empty() && lead.method != first;
      if (first.empty()) first = lead.method;
      parts.push_back(
          fmt::format("{} {} ({}{})", lead.method, at_level(a, l), share(lead),
                      verdict(lead) == Verdict::kHelps ? "" : ": no better than raw bump"));
    }
    if (changes)
      return fmt::format("The closest method changes with the {}: {}.", short_label(a),
                         list_text(parts));
  }
  return "";
}

// Whether `base`'s leader stays in the best rank group of every other
// ranking, and who leads where it does not. Rank groups, not first places:
// a leader tied with others has not lost to them. `opening` names the base
// ("Under the sun (light)"), `where` the word before another's id ("under",
// "on"), `what` the things compared ("lighting", "scene").
struct NamedRanking {
  std::string id;
  const RankingStatistics* ranking = nullptr;
};
std::string leader_holds_sentence(const std::string& opening, const RankingStatistics& base,
                                  const std::vector<NamedRanking>& others, const char* where,
                                  const char* what) {
  const MethodStatistics& lead = base.methods.front();
  std::vector<std::string> kept, lost;
  for (const NamedRanking& o : others) {
    const MethodStatistics* m = o.ranking->find(lead.method);
    if (!m || o.ranking->methods.empty()) continue;
    if (m->rank == 1) {
      kept.push_back(o.id);
      continue;
    }
    const MethodStatistics& other = o.ranking->methods.front();
    lost.push_back(fmt::format("{} (rank group {} at {}; {} leads at {})", o.id, m->rank, share(*m),
                               other.method, share(other)));
  }
  std::string out = fmt::format("{}, {} leads at {} of raw bump's combined error", opening,
                                lead.method, share(lead));
  if (lost.empty())
    return out + fmt::format(
                     " and stays in the best rank group {} all {} other {}s ({}): the ranking's "
                     "winner does not change with the {}.",
                     where, kept.size(), what, list_text(kept), what);
  out += fmt::format("; it falls out of the best rank group {} {}", where, list_text(lost, "; "));
  if (!kept.empty()) out += fmt::format(", and stays in it {} {}", where, list_text(kept));
  return out + fmt::format(": the winner changes with the {}.", what);
}

// For an axis of kinds of light (AxisStatistics::lighting): whether the
// first level's leader holds under the others.
std::string lighting_sentence(const StudyStatistics& s) {
  for (const AxisStatistics& a : s.by_axis) {
    if (!a.lighting || a.levels.empty() || a.levels.front().ranking.methods.empty()) continue;
    std::vector<NamedRanking> others;
    for (std::size_t l = 1; l < a.levels.size(); ++l)
      others.push_back({a.levels[l].value_id, &a.levels[l].ranking});
    return leader_holds_sentence(
        fmt::format("Under the {} ({})", a.levels.front().value_id, short_label(a)),
        a.levels.front().ranking, others, "under", "lighting");
  }
  return "";
}

// For a study of mesh assets (StudyStatistics::mesh_scenes): whether the
// first scene's leader (the study's reference shape) holds on every asset.
std::string scene_sentence(const StudyStatistics& s) {
  if (!s.mesh_scenes || s.per_scene.size() < 2 || s.per_scene.front().methods.empty()) return "";
  std::vector<NamedRanking> others;
  for (std::size_t i = 1; i < s.per_scene.size(); ++i)
    others.push_back({s.per_scene[i].scene, &s.per_scene[i]});
  return leader_holds_sentence(fmt::format("On the first scene ({})", s.per_scene.front().scene),
                               s.per_scene.front(), others, "on", "scene");
}

}  // namespace

std::vector<std::string> lead_sentences(const StudyStatistics& s) {
  std::vector<std::string> out;
  if (s.overall.methods.empty()) return out;
  out.push_back(leader_sentence(s.overall));
  if (std::string leaders = leaders_sentence(s); !leaders.empty()) out.push_back(leaders);
  out.push_back(worse_sentence(s.overall));
  if (std::string lighting = lighting_sentence(s); !lighting.empty())
    out.push_back(std::move(lighting));
  if (std::string scenes = scene_sentence(s); !scenes.empty()) out.push_back(std::move(scenes));
  const std::vector<Dependence> deps = dependences(s);
  std::size_t said = 0;
  for (std::size_t k = 0; k < deps.size() && said < 2; ++k)
    if (flips(*deps[k].first, deps[k].second->method)) {
      out.push_back(dependence_sentence(s, *deps[k].first, *deps[k].second));
      ++said;
    }
  // No method flips: the largest dependence still deserves its sentence.
  if (said == 0 && !deps.empty())
    out.push_back(dependence_sentence(s, *deps.front().first, *deps.front().second));
  if (deps.empty()) {
    std::size_t tests = 0;
    for (const AxisStatistics& a : s.by_axis) tests += a.interactions.size();
    out.push_back(fmt::format(
        "No method's effect depends on any axis's level at the 5 % level (permutation tests "
        "within matched variants, Holm-adjusted over {} tests).",
        tests));
  }
  if (std::string change = leader_change_sentence(s); !change.empty() && out.size() < 6)
    out.push_back(std::move(change));
  return out;
}

std::vector<std::string> quantity_notes(const StudyStatistics& s, const Plan& plan,
                                        const std::vector<ComparisonRow>& rows) {
  std::vector<std::string> out;
  const std::vector<RankEntry> absolute = rank_bump(plan, rows, "");
  const auto none = std::find_if(absolute.begin(), absolute.end(),
                                 [](const RankEntry& e) { return e.method == "none"; });
  if (none == absolute.end()) return out;
  for (const RankEntry& e : absolute) {
    const MethodStatistics* m = s.overall.find(e.method);
    if (!m || e.method == "none") continue;
    const bool below = e.mean < none->mean;  // absolute: better than raw bump
    const Verdict v = verdict(*m);
    if ((below && v != Verdict::kHurts) || (!below && v != Verdict::kHelps)) continue;
    std::string why;
    for (const auto& d : dependences(s))
      if (d.second->method == e.method) {
        // Where raw bump's absolute error is largest, which the absolute mean weighs most.
        const LevelRanking* heavy = nullptr;
        for (const LevelRanking& l : d.first->levels)
          if (const MethodStatistics* n = l.ranking.find("none");
              n && (!heavy || n->means[1].mean > heavy->ranking.find("none")->means[1].mean))
            heavy = &l;
        if (heavy)
          why = fmt::format(
              ", which are largest {} (raw bump {:.2f} % of albedo*E/pi), where {} is {} of raw "
              "bump's error",
              at_level(*d.first, *heavy), 100.0 * heavy->ranking.find("none")->means[1].mean,
              e.method, share(*heavy->ranking.find(e.method)));
        break;
      }
    out.push_back(fmt::format(
        "In the mean absolute terminator RMSE (a different quantity from the ranking metric), "
        "{} is {} raw bump ({:.2f} % against {:.2f} % of albedo*E/pi), while relative to raw bump "
        "in each variant it is {} ({} of raw bump's combined error): the absolute mean weighs "
        "each variant by the size of its errors{}; the ranking metric weighs every variant "
        "equally.",
        e.method, below ? "below" : "above", 100.0 * e.mean, 100.0 * none->mean,
        v == Verdict::kHurts ? "worse" : "better", share(*m), why));
  }
  return out;
}

}  // namespace penumbra
