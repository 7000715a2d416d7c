// The scene the project tests share: synthetic person 1 scanned with 40k
// points, fitted with two levels by fit_head directly, and projects fitted
// by the project's fit job.
#pragma once
#include "project/fit_job.h"
#include "test_scan.h"

#include <catch2/catch.hpp>

namespace lk::test {

inline FitHeadOptions quick_options() {
  FitHeadOptions o;
  o.levels = 2;
  return o;
}

// A 40k-point scan of synthetic person 1, fitted once by fit_head and once
// by the project's fit job.
struct ProjectScene {
  const GenericHead& generic = test::generic_head();
  test::TestScan person = test::make_test_scan(1, 40000);
  FitHeadResult direct;
  Status direct_status = fit_head(person.scan, generic, quick_options(), direct);
};

inline const ProjectScene& project_scene() {
  static const ProjectScene s;
  return s;
}

// A fresh project of the scene's scan (each test poses its own).
inline HeadProject fitted_project() {
  HeadProject p;
  const Status st = fit_project(project_scene().person.scan, project_scene().generic, quick_options(), p);
  INFO(st.message);
  REQUIRE(st.ok());
  return p;
}

}  // namespace lk::test
