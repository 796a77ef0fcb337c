// Self-check of the ThreadSanitizer job (scripts/tsan.sh), built there with the same compiler,
// flags, OpenMP runtime, Archer tool and suppressions as the library's TSan build.
//
//   openmp_canary clean   the OpenMP synchronisation errfield relies on (implicit barriers at the
//                         end of worksharing loops and parallel regions, explicit barriers,
//                         reductions, critical sections, atomics, dynamic schedules, one parallel
//                         region after another). Must run without a single TSan report: if it does
//                         not, TSan cannot see libomp's synchronisation (Archer missing or broken)
//                         and every report from the real tests would be suspect.
//   openmp_canary race    one genuine data race (two threads += the same double without
//                         synchronisation). Must be reported: if it is not, the job is blind (TSan
//                         not active, or a suppression too wide) and a green run would mean nothing.
//
// Not part of the library or of ctest; its exit status is all that matters.

#include <omp.h>

#include <cstdio>
#include <cstring>
#include <vector>

namespace {

int clean() {
  const int n = 20000;
  std::vector<double> a(n), b(n);
  double sum = 0.0, crit = 0.0;
  long atomic_count = 0;
#pragma omp parallel num_threads(2)
  {
#pragma omp for schedule(dynamic, 16)
    for (int i = 0; i < n; ++i) a[i] = 0.5 * i;
    // implicit barrier: every a[i] is now visible to both threads
#pragma omp for schedule(static) reduction(+ : sum)
    for (int i = 0; i < n; ++i) {
      b[i] = a[n - 1 - i];  // reads what the other thread wrote before the barrier
      sum += b[i];
    }
#pragma omp critical
    crit += 1.0;
#pragma omp atomic
    ++atomic_count;
#pragma omp barrier
#pragma omp single
    {
      if (crit != omp_get_num_threads()) std::printf("critical count %g\n", crit);
    }
  }
  // a second region reads and writes what the first one wrote (join, then fork)
  double sum2 = 0.0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(2) reduction(+ : sum2)
  for (int i = 0; i < n; ++i) {
    a[i] += b[i];
    sum2 += a[i];
  }
  const double expect = 0.5 * (n - 1.0) * n / 2.0;
  if (sum != expect || sum2 != 2.0 * expect || atomic_count != crit) {
    std::printf("wrong results: %g %g %ld\n", sum, sum2, atomic_count);
    return 2;
  }
  return 0;
}

int race() {
  const int n = 20000;
  std::vector<double> a(n, 1.0);
  double sum = 0.0;
#pragma omp parallel for schedule(static) num_threads(2)
  for (int i = 0; i < n; ++i) sum += a[i];  // deliberate race
  std::printf("racy sum %g\n", sum);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "clean") == 0) return clean();
  if (argc == 2 && std::strcmp(argv[1], "race") == 0) return race();
  std::fprintf(stderr, "usage: openmp_canary clean|race\n");
  return 2;
}
