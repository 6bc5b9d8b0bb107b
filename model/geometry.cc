#include "model/geometry.h"

#include "common/error.h"
#include "model/statics.h"

namespace cablecal {

std::vector<std::string> GeometryLayout::names() const {
  std::vector<std::string> out;
  for (int i = 1; i <= num_cables; ++i) {
    for (int axis = 0; axis < point_dim; ++axis) out.push_back("a" + std::to_string(i) + axes[axis]);
  }
  for (int i = 1; i <= num_cables; ++i) out.push_back("l" + std::to_string(i) + "0");
  return out;
}

std::string GeometryNameList(int num_cables, int from) {
  const std::vector<std::string> names = GeometryNames(num_cables);
  std::string list;
  for (std::size_t k = from; k < names.size(); ++k) list += (list.empty() ? "" : " ") + names[k];
  return list;
}

GeometryVector GeometryOf(const Robot& robot) {
  const GeometryLayout layout = LayoutOf(robot);
  const Eigen::VectorXd l0 = InitialLengths(robot);
  GeometryVector g(layout.size());
  for (int i = 0; i < layout.num_cables; ++i) {
    g.segment<kPlanarPointDim>(layout.exit(i, 0)) = robot.cables[i].p_F_exit_m;
    g(layout.initial_length(i)) = l0(i);
  }
  return g;
}

Robot WithGeometry(const Robot& robot, const GeometryVector& geometry) {
  const GeometryLayout layout = LayoutOf(robot);
  CABLECAL_CHECK(geometry.size() == layout.size(), "a geometry vector has one entry per exit coordinate and cable");
  Robot r = robot;
  for (int i = 0; i < layout.num_cables; ++i) {
    r.cables[i].p_F_exit_m = geometry.segment<kPlanarPointDim>(layout.exit(i, 0));
    r.cables[i].initial_length_m = geometry(layout.initial_length(i));
  }
  return r;
}

}  // namespace cablecal
