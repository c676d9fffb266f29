// Pushing bodies with the mouse: one interactive marker per moving body (~drag, rviz's InteractiveMarkers display).
// Dragging it pulls the grabbed point of the body towards the marker with a critically damped spring of natural
// frequency ~drag_frequency (world_commands.h ApplyDragFeedback); the spring is drawn as an arrow (~markers, ns
// "drag") and released when the drag ends. The markers follow the bodies from the snapshots. Its own lock.
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include <interactive_markers/interactive_marker_server.h>
#include <ros/ros.h>

#include "implicit_sim/core/model/model.h"
#include "implicit_sim/core/model/state.h"
#include "implicit_sim/ros/node_publisher.h"

namespace implicit_sim {

class DragMarkers {
 public:
  using Feedback = visualization_msgs::InteractiveMarkerFeedbackConstPtr;
  // on_feedback receives the markers' events (on a ROS callback thread); nothing is served unless `enabled`.
  DragMarkers(ros::NodeHandle pnh, const std::string& world_frame, bool enabled,
              std::function<void(const Feedback&)> on_feedback);
  ~DragMarkers();

  // One marker per moving body of a (new) world.
  void SetUp(const Model& model, const State& state);
  // Moves the markers to the bodies of a newer snapshot, at most every 0.1 s of wall time (publish thread); a body
  // being dragged keeps the user's marker.
  void Follow(const NodeSnapshot& snapshot);
  void SetDragged(const std::string& body, bool dragged);

 private:
  ros::NodeHandle pnh_;
  const std::string world_frame_;
  const std::function<void(const Feedback&)> on_feedback_;
  std::unique_ptr<interactive_markers::InteractiveMarkerServer> server_;
  std::mutex mutex_;
  std::set<std::string> dragged_;  // bodies being dragged (their marker is the user's); guarded by mutex_
  double next_update_ = 0.0;  // publish thread: s of wall time, the next pose update
  uint64_t version_ = 0;      // publish thread: the snapshot version the markers show
};

}  // namespace implicit_sim
