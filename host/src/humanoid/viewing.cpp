#include "hmpc/humanoid/viewing.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>

#include "hmpc/humanoid/physical_checks.hpp"

namespace hmpc::humanoid {
namespace {

const char* const kLegNames[2] = {"left", "right"};
const char* const kJointNames[kJointsPerLeg] = {"hip_abduction", "hip_flexion", "knee", "ankle"};

void write_point(std::ostream& out, const Vector3& p, const Vector3& centre) {
  out << p.x() - centre.x() << ' ' << p.y() - centre.y() << ' ' << p.z() << '\n';
}

// One frame: polylines separated by blank lines, coordinates relative to the base's (x, y).
void write_frame(std::ostream& out, const StickFigure& f, const Motion& motion) {
  const Vector3 centre = f.mid_hip;
  write_point(out, f.vertex, centre);
  write_point(out, f.mid_hip, centre);
  out << '\n';
  write_point(out, f.hip[0], centre);
  write_point(out, f.hip[1], centre);
  out << '\n';
  for (int leg = 0; leg < 2; ++leg) {
    for (const Vector3& p :
         {f.hip[leg], f.knee[leg], f.ankle[leg], f.heel[leg], f.toe[leg], f.ankle[leg]}) {
      write_point(out, p, centre);
    }
    out << '\n';
  }
  if (motion.chair) {
    write_point(out, Vector3(motion.seat_x_min, centre.y() - 0.25, motion.seat_height), centre);
    write_point(out, Vector3(motion.seat_x_max, centre.y() + 0.25, motion.seat_height), centre);
    out << '\n';
  }
  if (f.arm) {
    write_point(out, f.spine, centre);
    write_point(out, f.shoulder, centre);
    write_point(out, f.hand, centre);
    out << '\n';
  }
  if (motion.reach.active) {  // the target as a small cross in both views
    const Vector3& p = motion.reach.target;
    for (const Vector3& d : {Vector3(0.03, 0.03, 0.0), Vector3(0.0, 0.0, 0.03)}) {
      write_point(out, p - d, centre);
      write_point(out, p + d, centre);
      out << '\n';
    }
  }
}

bool fail(std::string& error, const std::string& message) {
  error = message;
  return false;
}

}  // namespace

template <int A>
StickFigure stick_figure(const BasicState<A>& x, const ProblemConfig& config) {
  using Model = BasicModel<A>;
  const Model model(config.parameters);
  const BasicDynamics<A> dynamics(model);
  const BasicContactModel<A> contact(model, config.parameters, config.contact);
  BasicKinematics<A> kin;
  dynamics.kinematics(x.q, x.v, kin);
  BasicContactState<A> points;
  contact.evaluate(kin, x.v, points);
  StickFigure f;
  f.mid_hip = kin.position[0];
  f.vertex = kin.position[0] + kin.rotation[0] * model.vertex;
  for (int leg = 0; leg < 2; ++leg) {
    f.hip[leg] = kin.position[Model::body_of(leg, kHipFlexion)];
    f.knee[leg] = kin.position[Model::body_of(leg, kKnee)];
    f.ankle[leg] = kin.position[Model::body_of(leg, kAnkle)];
    // Sole points 0-1 of a foot are at the heel, 2-3 at the toe (contact.cpp).
    const int first = leg * kFootPoints;
    f.heel[leg] = 0.5 * (points.position[first] + points.position[first + 1]);
    f.toe[leg] = 0.5 * (points.position[first + 2] + points.position[first + 3]);
  }
  if constexpr (A == 1) {
    const int arm = Dimensions<A>::kArmBody;
    f.arm = true;
    const Vector3& shoulder = model.bodies[arm].joint_origin;  // torso coordinates
    f.spine = kin.position[0] + kin.rotation[0] * Vector3(0.0, 0.0, shoulder.z());
    f.shoulder = kin.position[arm];
    f.hand = hand_position(model, kin);
  }
  return f;
}

template <int A>
void write_trajectory_csv(std::ostream& out, const Motion& motion,
                          const BasicClosedLoopRun<A>& run) {
  constexpr int kJoints = Dimensions<A>::kJoints;
  out << "time,base_x,base_y,base_z,base_vx,base_vy,base_vz,quat_w,quat_x,quat_y,quat_z,"
         "alpha_left,alpha_right,beta_left,beta_right";
  for (const char* leg : kLegNames)
    for (const char* joint : kJointNames) out << ',' << leg << '_' << joint;
  if (A == 1) out << ",right_shoulder_flexion";
  for (const char* leg : kLegNames)
    for (const char* joint : kJointNames) out << ",torque_" << leg << '_' << joint;
  if (A == 1) out << ",torque_right_shoulder_flexion";
  out << ",force_left,force_right,force_seat,solve_ms,iterations,fast_iterations,truncated,"
         "plan_usable,cost,target_height,target_vx,target_vy,target_vz,target_roll,target_pitch,"
         "target_yaw";
  if (A == 1) out << ",hand_x,hand_y,hand_z,reach_x,reach_y,reach_z";
  out << '\n';
  out.precision(9);
  for (const BasicClosedLoopSample<A>& s : run.samples) {
    const BaseFeatures& b = s.base;
    out << s.time << ',' << b.position.x() << ',' << b.position.y() << ',' << b.position.z() << ','
        << b.velocity.x() << ',' << b.velocity.y() << ',' << b.velocity.z() << ','
        << b.quaternion[0] << ',' << b.quaternion[1] << ',' << b.quaternion[2] << ','
        << b.quaternion[3] << ',' << b.alpha_left << ',' << b.alpha_right << ',' << b.beta_left
        << ',' << b.beta_right;
    for (int i = 0; i < kJoints; ++i) out << ',' << s.state.q[7 + i];
    for (int i = 0; i < kJoints; ++i) out << ',' << s.torque[i];
    const Phase& target = motion.phase_at(s.time);
    const Eigen::Vector3d target_velocity = target.velocity_at(s.time);
    out << ',' << s.left_force << ',' << s.right_force << ',' << s.seat_force << ','
        << s.solve_seconds * 1e3 << ',' << s.iterations << ',' << s.fast_iterations << ','
        << (s.truncated ? 1 : 0) << ',' << (s.plan_usable ? 1 : 0) << ',' << s.cost << ','
        << target.height_at(s.time) << ',' << target_velocity.x() << ',' << target_velocity.y()
        << ',' << target_velocity.z() << ',' << target.attitude.x() << ',' << target.attitude.y()
        << ',' << target.attitude.z();
    if (A == 1) {
      const Vector3& reach = motion.reach.target;
      out << ',' << s.base.hand.x() << ',' << s.base.hand.y() << ',' << s.base.hand.z() << ','
          << reach.x() << ',' << reach.y() << ',' << reach.z();
    }
    out << '\n';
  }
}

namespace {

// Roll and pitch [rad] of the torso (Z-Y-X Euler angles, which do not depend on the yaw).
template <int A>
Eigen::Vector2d roll_pitch(const BasicState<A>& x) {
  const Eigen::Quaterniond q(x.q[3], x.q[4], x.q[5], x.q[6]);
  const Vector3 up = q.conjugate() * Vector3::UnitZ();  // world's up in torso coordinates
  return {std::atan2(up.y(), up.z()), -std::asin(std::clamp(up.x(), -1.0, 1.0))};
}

// Horizontal velocity of the torso origin, world (v's linear part is in torso coordinates).
template <int A>
Eigen::Vector2d horizontal_velocity(const BasicState<A>& x) {
  const Eigen::Quaterniond q(x.q[3], x.q[4], x.q[5], x.q[6]);
  return (q * x.v.template segment<3>(3)).template head<2>();
}

}  // namespace

template <int A>
void write_estimation_csv(std::ostream& out, const BasicClosedLoopRun<A>& run) {
  out << "time,true_z,estimated_z,sigma_z,true_vx,true_vy,estimated_vx,estimated_vy,"
         "sigma_horizontal_v,true_roll,true_pitch,estimated_roll,estimated_pitch,sigma_tilt,"
         "trust\n";
  out.precision(9);
  const BasicState<A>* truth = &run.initial;  // at the first period's start
  double time = 0.0;
  for (const BasicClosedLoopSample<A>& s : run.samples) {
    const Eigen::Vector2d v = horizontal_velocity(*truth), v_fed = horizontal_velocity(s.feedback);
    const Eigen::Vector2d a = roll_pitch(*truth), a_fed = roll_pitch(s.feedback);
    out << time << ',' << truth->q[2] << ',' << s.feedback.q[2] << ',' << s.spread.height << ','
        << v.x() << ',' << v.y() << ',' << v_fed.x() << ',' << v_fed.y() << ','
        << s.spread.horizontal_velocity << ',' << a.x() << ',' << a.y() << ',' << a_fed.x() << ','
        << a_fed.y() << ',' << s.spread.tilt << ',' << static_cast<int>(s.trust) << '\n';
    truth = &s.state;
    time = s.time;
  }
}

template <int A>
bool write_run(const std::string& dir, const std::string& title, const Motion& motion,
               const BasicClosedLoopRun<A>& run, int frames, std::string& error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return fail(error, "cannot create " + dir + ": " + ec.message());
  const fs::path base(dir);
  {
    std::ofstream csv(base / "trajectory.csv");
    write_trajectory_csv(csv, motion, run);
    if (!csv) return fail(error, "cannot write " + (base / "trajectory.csv").string());
  }
  if (run.samples.empty()) return fail(error, "the run has no samples to draw");
  frames = std::clamp(frames, 2, 16);
  const int count = static_cast<int>(run.samples.size());
  std::string times;
  double top = 1.0;
  {
    std::ofstream dat(base / "filmstrip.dat");
    dat.precision(6);
    for (int i = 0; i < frames; ++i) {
      const BasicClosedLoopSample<A>& s = run.samples[(count - 1) * i / (frames - 1)];
      const StickFigure f = stick_figure(s.state);
      top = std::max({top, f.vertex.z(), f.toe[0].z(), f.toe[1].z(), f.hand.z()});
      dat << "# t = " << s.time << " s\n";
      write_frame(dat, f, motion);
      dat << "\n";
      char t[32];
      std::snprintf(t, sizeof t, "%s%.2f", i == 0 ? "" : " ", s.time);
      times += t;
    }
    if (!dat) return fail(error, "cannot write " + (base / "filmstrip.dat").string());
  }
  const fs::path script = base / "humanoid.gp";
  {
    std::ofstream gp(script);
    gp << "# gnuplot " << script.filename().string()
       << " (in this directory) redraws the pictures\n"
       << "set terminal pngcairo size " << 190 * frames << ",560 noenhanced\n"
       << "set output 'filmstrip.png'\n"
       << "times = '" << times << "'\n"
       << "set multiplot layout 2," << frames << " title '" << title
       << " (side x-z above, front y-z below)'\n"
       << "unset key\nset size ratio -1\nset xrange [-0.8:0.8]\nset yrange [-0.05:" << top + 0.1
       << "]\n"
       << "set xtics 0.4 font ',8'\nset ytics 0.5 font ',8'\n"
       << "do for [i=0:" << frames - 1 << "] { set title word(times, i+1).' s'; "
       << "plot 'filmstrip.dat' index i using 1:3 with lines lw 2 lc rgb '#1f4e99', 0 lc rgb "
          "'gray' }\n"
       << "do for [i=0:" << frames - 1 << "] { set title word(times, i+1).' s'; "
       << "plot 'filmstrip.dat' index i using 2:3 with lines lw 2 lc rgb '#99321f', 0 lc rgb "
          "'gray' }\n"
       << "unset multiplot\n"
       << "set terminal pngcairo size 900," << (A == 1 ? 900 : 640)
       << " noenhanced\nset output 'base.png'\n"
       << "set datafile separator ','\nset size noratio\nset autoscale\nunset title\n"
       << "set xtics autofreq font ''\nset ytics autofreq font ''\nset key outside top center "
          "horizontal\n"
       << "set multiplot layout " << (A == 1 ? 3 : 2) << ",1 title '" << title << "'\n"
       << "set ylabel 'height [m]'\nplot 'trajectory.csv' using 1:" << kHeightColumn
       << " with lines lw 2 title 'base point', "
       << "'' using 1:" << kTargetHeightColumn<A> << " with steps dt 2 title 'target'\n";
    if (A == 1) {
      // The hand's distance to the reach target, from the columns after target_yaw.
      const int hand = kTargetHeightColumn<A> + 7, reach = hand + 3;
      gp << "set ylabel 'hand to target [m]'\nplot 'trajectory.csv' using 1:(sqrt(";
      for (int k = 0; k < 3; ++k) {
        gp << (k == 0 ? "" : "+") << "(column(" << hand + k << ")-column(" << reach + k << "))**2";
      }
      gp << ")) with lines lw 2 title 'hand', " << kReachTolerance << " dt 2 title '5 cm'\n";
    }
    gp << "set xlabel 'time [s]'\nset ylabel 'v_x [m/s]'\nplot 'trajectory.csv' using 1:"
       << kVelocityColumn << " with lines lw 2 "
       << "title 'base point', '' using 1:" << kTargetHeightColumn<A> + 1
       << " with steps dt 2 title 'target'\n"
       << "unset multiplot\n";
    if (!gp) return fail(error, "cannot write " + script.string());
  }
  if (run.feedback != StateFeedback::kTruth) {
    {
      std::ofstream csv(base / "estimation.csv");
      write_estimation_csv(csv, run);
      if (!csv) return fail(error, "cannot write " + (base / "estimation.csv").string());
    }
    std::ofstream gp(script, std::ios::app);
    gp << "set terminal pngcairo size 900,900 noenhanced\nset output 'estimation.png'\n"
       << "set multiplot layout 3,1 title '" << title << ": " << name_of(run.feedback)
       << " against the truth'\nunset xlabel\n"
       << "set ylabel 'torso height [m]'\nplot 'estimation.csv' using 1:($3-2*$4):($3+2*$4) "
          "with filledcurves fc rgb '#cfd8ea' title 'estimate +-2 sigma', '' using 1:2 with "
          "lines lw 2 lc rgb 'black' title 'truth', '' using 1:3 with lines lw 1 lc rgb "
          "'#1f4e99' title 'estimate'\n"
       << "set ylabel 'horizontal velocity [m/s]'\nplot 'estimation.csv' using 1:5 with lines "
          "lw 2 lc rgb 'black' title 'v_x truth', '' using 1:7 with lines lc rgb '#1f4e99' "
          "title 'v_x estimate', '' using 1:6 with lines lw 2 lc rgb 'gray' title 'v_y truth', "
          "'' using 1:8 with lines lc rgb '#99321f' title 'v_y estimate'\n"
       << "set xlabel 'time [s]'\nset ylabel 'tilt [deg]'\nplot 'estimation.csv' using "
          "1:($10*180/pi) with lines lw 2 lc rgb 'black' title 'roll truth', '' using "
          "1:($12*180/pi) with lines lc rgb '#1f4e99' title 'roll estimate', '' using "
          "1:($11*180/pi) with lines lw 2 lc rgb 'gray' title 'pitch truth', '' using "
          "1:($13*180/pi) with lines lc rgb '#99321f' title 'pitch estimate'\n"
       << "unset multiplot\n";
    if (!gp) return fail(error, "cannot write " + script.string());
  }
  const std::string command = "cd '" + dir + "' && gnuplot humanoid.gp 2> gnuplot.log";
  if (std::system(command.c_str()) != 0) {
    return fail(error, "gnuplot failed (see " + (base / "gnuplot.log").string() +
                           "); install it with toolchains/setup-debian.sh");
  }
  return true;
}

template StickFigure stick_figure(const BasicState<0>&, const ProblemConfig&);
template StickFigure stick_figure(const BasicState<1>&, const ProblemConfig&);
template void write_trajectory_csv(std::ostream&, const Motion&, const BasicClosedLoopRun<0>&);
template void write_trajectory_csv(std::ostream&, const Motion&, const BasicClosedLoopRun<1>&);
template void write_estimation_csv(std::ostream&, const BasicClosedLoopRun<0>&);
template void write_estimation_csv(std::ostream&, const BasicClosedLoopRun<1>&);
template bool write_run(const std::string&, const std::string&, const Motion&,
                        const BasicClosedLoopRun<0>&, int, std::string&);
template bool write_run(const std::string&, const std::string&, const Motion&,
                        const BasicClosedLoopRun<1>&, int, std::string&);

}  // namespace hmpc::humanoid
