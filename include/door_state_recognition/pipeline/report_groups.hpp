#pragma once
// The station merge's grouping of door reports (pipeline/stations.cpp), on
// its own so that tests can give it reports of their own making.
#include <cstddef>
#include <functional>
#include <vector>

namespace dsr {
namespace stations {

// Groups reports 0..n-1 of a survey into doors: the connected parts of
// `same` (a report the same door as two others joins them). Two reports of
// one station that are the same door are joined first (a station's
// duplicate); then the pairs of different stations, nearest first
// (`distance`, ties in report order), except that two parts that each hold
// a report of one station are never joined: a station's reports that are not
// the same door are two doors, and a report of another station overlapping
// both joins the one it lies nearer. station_of[i] is the station of report
// i. Each group lists its reports in order; groups are ordered by their
// first report.
std::vector<std::vector<std::size_t>> groupReports(const std::vector<int>& station_of,
                                                   const std::function<bool(std::size_t, std::size_t)>& same,
                                                   const std::function<double(std::size_t, std::size_t)>& distance);

}  // namespace stations
}  // namespace dsr
