// rostest of the camera path: the node paints a cloud that has no evidence field with a label
// image (left half building, right half road) through CameraInfo and the lidar -> camera TF.
#include <cstring>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "evidential_octomap/QueryMap.h"

namespace {

constexpr int kBuilding = 13, kRoad = 9;
const std::string kNode = "/evidential_mapping_node";

geometry_msgs::TransformStamped transform(const std::string& parent, const std::string& child,
                                          double qx, double qy, double qz, double qw) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.rotation.x = qx;
  t.transform.rotation.y = qy;
  t.transform.rotation.z = qz;
  t.transform.rotation.w = qw;
  return t;
}

// x, y, z only: every point gets its evidence from the image.
sensor_msgs::PointCloud2 cloudOf(const std::vector<float>& xyz, const ros::Time& stamp) {
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = "lidar";
  msg.header.stamp = stamp;
  const char* axes[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    sensor_msgs::PointField f;
    f.name = axes[i];
    f.offset = 4 * i;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    msg.fields.push_back(f);
  }
  msg.point_step = 12;
  msg.height = 1;
  msg.width = xyz.size() / 3;
  msg.row_step = msg.point_step * msg.width;
  msg.data.resize(msg.row_step);
  std::memcpy(msg.data.data(), xyz.data(), msg.row_step);
  return msg;
}

geometry_msgs::Point gp(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x;
  p.y = y;
  p.z = z;
  return p;
}

}  // namespace

TEST(CameraPath, PointsTakeTheClassOfTheirPixel) {
  ros::NodeHandle nh;
  ros::Publisher cloud_pub = nh.advertise<sensor_msgs::PointCloud2>("cloud_in", 5);
  ros::Publisher image_pub = nh.advertise<sensor_msgs::Image>("image_in", 5);
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("camera_info", 5);
  tf2_ros::StaticTransformBroadcaster tf;
  // map -> lidar identity; lidar -> camera: the usual optical frame (z forward, x right, y down).
  tf.sendTransform(std::vector<geometry_msgs::TransformStamped>{
      transform("map", "lidar", 0, 0, 0, 1), transform("lidar", "camera", -0.5, 0.5, -0.5, 0.5)});
  ASSERT_TRUE(ros::service::waitForService(kNode + "/query", ros::Duration(60)));
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(60);
  while ((cloud_pub.getNumSubscribers() == 0 || image_pub.getNumSubscribers() == 0 ||
          info_pub.getNumSubscribers() == 0) && ros::WallTime::now() < give_up)
    ros::WallDuration(0.05).sleep();

  // 100 x 80 label image: columns < 50 building, the rest road. f = 100, centre (50, 40).
  const ros::Time stamp = ros::Time::now();
  sensor_msgs::Image image;
  image.header.stamp = stamp;
  image.header.frame_id = "camera";
  image.width = 100;
  image.height = 80;
  image.encoding = "mono8";
  image.step = 100;
  image.data.resize(100 * 80);
  for (int r = 0; r < 80; ++r)
    for (int c = 0; c < 100; ++c) image.data[r * 100 + c] = c < 50 ? kBuilding : kRoad;
  sensor_msgs::CameraInfo info;
  info.header = image.header;
  info.width = 100;
  info.height = 80;
  info.distortion_model = "plumb_bob";
  info.D = {0, 0, 0, 0, 0};
  info.K = {100, 0, 50, 0, 100, 40, 0, 0, 1};

  // A wall 4 m ahead (y left: image left = building), and points behind the camera (dropped).
  std::vector<float> xyz;
  for (float y = -1.f; y <= 1.f; y += 0.05f)
    for (float z = -0.3f; z <= 0.3f; z += 0.05f) {
      xyz.insert(xyz.end(), {4.05f, y, z});
      xyz.insert(xyz.end(), {-4.05f, y, z});
    }

  evidential_octomap::QueryMap srv;
  srv.request.points = {gp(4.05, 0.6, 0.1), gp(4.05, -0.6, 0.1), gp(-4.05, 0.0, 0.1)};
  // Images are matched to clouds by stamp: send the image first, then the cloud, until the map
  // answers (the first messages may go out before the node's subscriptions are connected).
  bool mapped = false;
  for (int attempt = 0; attempt < 20 && !mapped; ++attempt) {
    image_pub.publish(image);
    info_pub.publish(info);
    ros::WallDuration(0.3).sleep();
    cloud_pub.publish(cloudOf(xyz, stamp));
    ros::WallDuration(1.0).sleep();
    ASSERT_TRUE(ros::service::call(kNode + "/query", srv));
    mapped = srv.response.labels[0] >= 0;
  }
  ASSERT_TRUE(mapped) << "the camera-painted cloud never reached the map";
  EXPECT_EQ(srv.response.labels[0], kBuilding);     // left of the optical axis
  EXPECT_EQ(srv.response.labels[1], kRoad);         // right of it
  EXPECT_FLOAT_EQ(srv.response.occupancy[2], -1.f); // behind the camera: dropped, not mapped
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_camera_node");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
