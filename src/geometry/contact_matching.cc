#include "geometry/contact_matching.h"

#include <algorithm>
#include <bit>
#include <utility>

namespace rigidtouch::geometry {

void ContactMatching::Reserve(int max_contacts, int ngeom) {
  previous.assign(static_cast<std::size_t>(max_contacts), Contact{});
  previous_runs.assign(static_cast<std::size_t>(max_contacts), PairRun{});
  run_start.assign(static_cast<std::size_t>(ngeom) + 1, 0);
  run_fill.assign(static_cast<std::size_t>(ngeom), 0);
  Reset();
}

void ContactMatching::Reset() {
  nprevious = 0;
  nprevious_runs = 0;
  next_contact_id = 0;
}

bool RunsIndexList(const Data& data) {
  if (data.nruns > static_cast<int>(data.runs.size())) return false;
  int next = 0;
  for (int r = 0; r < data.nruns; ++r) {
    const PairRun& run = data.runs[r];
    if (run.begin != next || run.count < 1) return false;
    next += run.count;
  }
  return next == data.ncontact;
}

// last tick's contacts become `previous` (the buffers trade places, no copy), and the runs of
// their geom pairs are indexed for MatchPair: m.previous_runs sorted by pair, the runs whose
// first geom is g at previous_runs[run_start[g] .. run_start[g + 1]). A counting sort on the first
// geom replaces a comparison sort; DetectContacts writes each geom pair in one run at most, so
// the order is the one a sort by pair gives. The runs are last tick's data.runs when they index
// its list (RunsIndexList), else found in the list.
void RememberPrevious(Data& data, ContactMatching& m) {
  const bool indexed = RunsIndexList(data);
  const int nlast = data.nruns;
  std::swap(data.contacts, m.previous);
  m.nprevious = data.ncontact;
  data.ncontact = 0;
  data.nruns = 0;
  const Contact* prev = m.previous.data();
  const int nprev = m.nprevious;
  const PairRun* last = data.runs.data();  // written again only after the index is made
  // calls f(run) for each run of one geom pair, in list order
  auto for_each_run = [indexed, last, nlast, prev, nprev](auto&& f) {
    if (indexed) {
      for (int r = 0; r < nlast; ++r) f(last[r]);
      return;
    }
    for (int begin = 0; begin < nprev;) {
      const Contact& c = prev[begin];
      int end = begin + 1;
      while (end < nprev && prev[end].geom_a == c.geom_a && prev[end].geom_b == c.geom_b) ++end;
      f(PairRun{c.geom_a, c.geom_b, c.body_a, c.body_b, begin, end - begin});
      begin = end;
    }
  };
  std::vector<int>& start = m.run_start;
  std::vector<int>& fill = m.run_fill;
  std::fill(start.begin(), start.end(), 0);
  int nruns = 0;
  for_each_run([&start, &nruns](const PairRun& run) {
    ++start[run.geom_a + 1];
    ++nruns;
  });
  const int ngeom = static_cast<int>(fill.size());
  for (int g = 0; g < ngeom; ++g) {
    start[g + 1] += start[g];
    fill[g] = start[g];
  }
  PairRun* runs = m.previous_runs.data();
  for_each_run([&start, &fill, runs](const PairRun& run) {
    // insertion into its first geom's bucket, sorted by the second geom
    const int ga = run.geom_a;
    int j = fill[ga]++;
    for (; j > start[ga] && runs[j - 1].geom_b > run.geom_b; --j) runs[j] = runs[j - 1];
    runs[j] = run;
  });
  m.nprevious_runs = nruns;
}

// matches the contacts of one geom pair [begin, end) in data.contacts against last tick's. A new
// point gets no id here (-1): AssignNewIds gives the ids, in contact order, so that the two
// threads, which match pairs in any order, number new contacts as one thread would. Returns
// whether the pair has a new point. Reads only last tick's contacts and the pair's own.
bool MatchPair(Data& data, const ContactMatching& m, int begin, int end) {
  const Contact& key = data.contacts[begin];
  // last tick's run of this pair, if any
  const PairRun* run = nullptr;
  for (int r = m.run_start[key.geom_a]; r < m.run_start[key.geom_a + 1]; ++r) {
    if (m.previous_runs[r].geom_b == key.geom_b) {
      run = &m.previous_runs[r];
      break;
    }
  }
  const Contact* lo = m.previous.data() + (run != nullptr ? run->begin : 0);
  const int nprev = run != nullptr ? run->count : 0;
  const int ncur = end - begin;
  // a pair with one point before and now is the same contact wherever it slid
  const bool single = nprev == 1 && ncur == 1;
  // greedy nearest matching; a manifold has at most a few points. The candidates are last tick's
  // first 32 points not matched yet, one bit each: visiting the set bits from the lowest keeps the
  // index order, so ties still go to the lowest index, without a test per matched point.
  unsigned unused = nprev >= 32 ? ~0u : (1u << nprev) - 1u;
  bool any_new = false;
  for (int c = begin; c < end; ++c) {
    Contact& con = data.contacts[c];
    int best = single ? 0 : -1;
    if (!single) {
      double best_d2 = kMatchDistance_m * kMatchDistance_m;
      for (unsigned left = unused; left != 0; left &= left - 1) {
        const int k = std::countr_zero(left);
        const double d2 = (lo[k].p_A - con.p_A).squaredNorm();
        if (d2 < best_d2) {
          best = k;
          best_d2 = d2;
        }
      }
    }
    con.pair_points = ncur;
    if (best >= 0) {
      unused &= ~(1u << best);
      const Contact& prev = lo[best];
      con.id = prev.id;
      con.is_new = false;
      con.sticking = prev.sticking;
      con.anchor_A = prev.anchor_A;
      con.anchor_B = prev.anchor_B;
      con.phase = prev.phase;
    } else {
      con.id = -1;
      con.is_new = true;
      con.sticking = false;
      con.anchor_A = con.p_A;
      con.anchor_B = con.p_B;
      con.phase = ContactPhase::kResting;
      any_new = true;
    }
  }
  return any_new;
}

// the ids of the new points of the pair [begin, end) that MatchPair left without one
void AssignNewIds(Data& data, ContactMatching& m, int begin, int end) {
  for (int c = begin; c < end; ++c) {
    if (data.contacts[c].id < 0) data.contacts[c].id = m.next_contact_id++;
  }
}

// MatchPair and AssignNewIds on one thread, and the pair's run appended to data.runs (a buffer
// smaller than the contact list's, in a Data not made by MakeData, leaves the index short:
// RunsIndexList then says so, and the list is read instead)
void MatchAndNumber(Data& data, ContactMatching& m, int begin, int end) {
  if (MatchPair(data, m, begin, end)) AssignNewIds(data, m, begin, end);
  if (data.nruns >= static_cast<int>(data.runs.size())) return;
  const Contact& first = data.contacts[begin];
  data.runs[data.nruns++] =
      PairRun{first.geom_a, first.geom_b, first.body_a, first.body_b, begin, end - begin};
}

}  // namespace rigidtouch::geometry
