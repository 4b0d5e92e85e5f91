"""The ROS bag reader (magexp.core.readers.rosbag) on ROS 1 bags, ROS 2 bags and MCAP files written
by rosbags' own writer, and its vectorised decoder against rosbags' serialiser."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from magexp.core.logfiles import NED_TO_ENU
from magexp.errors import MagexpError
from magexp.core.geometry import random_rotations
from magexp.core.recordings import load_recording

@functools.lru_cache(maxsize=2)
def typestore(ros1: bool):
    """rosbags' built-in message definitions (0.2-0.3 s to build: once)."""
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)


LAT, LON, ALT = 47.3977, 8.5456, 488.0
STAMP = 1_750_000_000  # 2025-06-15


def write_bag(path, kind: str, rotations: np.ndarray, field_ned: np.ndarray, w=np.eye(3), offset=np.zeros(3)) -> np.ndarray:
    """A bag of MagneticField (T) + Imu (orientation body -> ENU) + NavSatFix at the same stamps, the
    sensor at ``rotations`` (body -> NED) reading ``r = W⁻¹ B + o`` (µT); returns the readings."""
    ros1 = kind == "ros1"
    ts = typestore(ros1)
    t = ts.types
    body = np.einsum("nji,j->ni", rotations, field_ned) / 1e3  # nav -> body = R^T, nT -> µT
    readings_ut = np.linalg.solve(w, body.T).T + offset
    body_to_enu = NED_TO_ENU @ rotations
    from scipy.spatial.transform import Rotation

    q = Rotation.from_matrix(body_to_enu).as_quat()  # x, y, z, w
    if ros1:
        from rosbags.rosbag1 import Writer
        writer, serialize = Writer(path), ts.serialize_ros1
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer
        plugin = StoragePlugin.MCAP if kind == "mcap" else StoragePlugin.SQLITE3
        writer, serialize = Writer(path, version=9, storage_plugin=plugin), ts.serialize_cdr
    with writer:
        conns = {name: writer.add_connection(topic, name, typestore=ts) for name, topic in (
            ("sensor_msgs/msg/MagneticField", "/imu/mag"), ("sensor_msgs/msg/Imu", "/imu/data"),
            ("sensor_msgs/msg/NavSatFix", "/gps/fix"))}
        for k in range(len(rotations)):
            ns = STAMP * 10**9 + k * 10**7
            header = t["std_msgs/msg/Header"](seq=k, stamp=t["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9),
                                              frame_id="imu") if ros1 else \
                t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9),
                                         frame_id="imu")
            v3 = lambda x: t["geometry_msgs/msg/Vector3"](x=float(x[0]), y=float(x[1]), z=float(x[2]))  # noqa: E731
            mag = t["sensor_msgs/msg/MagneticField"](header=header, magnetic_field=v3(readings_ut[k] * 1e-6),
                                                     magnetic_field_covariance=np.zeros(9))
            imu = t["sensor_msgs/msg/Imu"](
                header=header, orientation=t["geometry_msgs/msg/Quaternion"](x=q[k, 0], y=q[k, 1], z=q[k, 2], w=q[k, 3]),
                orientation_covariance=np.zeros(9), angular_velocity=v3([0.01, -0.02, 0.03]),
                angular_velocity_covariance=np.zeros(9), linear_acceleration=v3([0, 0, 9.81]),
                linear_acceleration_covariance=np.zeros(9))
            fix = t["sensor_msgs/msg/NavSatFix"](header=header, status=t["sensor_msgs/msg/NavSatStatus"](status=0, service=1),
                                                 latitude=LAT, longitude=LON, altitude=ALT, position_covariance=np.zeros(9),
                                                 position_covariance_type=0)
            for name, msg in (("sensor_msgs/msg/MagneticField", mag), ("sensor_msgs/msg/Imu", imu),
                              ("sensor_msgs/msg/NavSatFix", fix)):
                writer.write(conns[name], ns, serialize(msg, name))
    return readings_ut


@pytest.mark.parametrize("kind, name", [("ros2", "bag2"), ("mcap", "bag_mcap"), ("ros1", "flight.bag")])
def test_ros_bags_round_trip(tmp_path, kind, name):
    rotations = random_rotations(40, rng=np.random.default_rng(7))
    field_ned = np.array([21000.0, 1500.0, 43000.0])
    path = tmp_path / name
    readings = write_bag(path, kind, rotations, field_ned)
    target = path if kind != "mcap" else next(path.glob("*.mcap"))  # the bare .mcap file opens too
    rec = load_recording(target)
    assert rec.meta["format"] == "rosbag" and rec.unit == "uT" and rec.n == 40
    np.testing.assert_allclose(rec.readings, readings, rtol=1e-12)
    # the attitude read back (NED) turns the NED field into the readings: the ENU -> NED conversion holds
    np.testing.assert_allclose(np.einsum("nij,j->ni", rec.attitude(), field_ned) / 1e3, readings, atol=1e-9)
    np.testing.assert_allclose(rec.times, np.arange(40) * 0.01, atol=1e-6)
    assert rec.gyro_stream[1][0].tolist() == pytest.approx([0.01, -0.02, 0.03])
    assert float(rec.meta["latitude"]) == LAT and float(rec.meta["altitude_km"]) == ALT / 1e3
    assert rec.meta["date"] == "2025-06-15"


@pytest.mark.parametrize("ros1", [False, True], ids=["cdr", "ros1"])
def test_the_vectorised_decoder_reads_what_rosbags_wrote(ros1):
    """Messages of every frame_id length (the CDR alignment after it varies), serialised by rosbags,
    decoded field by field for all at once; a message cut short or padded is a LayoutError."""
    from magexp.core.readers.rosbag import FIX, IMU, MAG, LayoutError, decode

    ts, rng = typestore(ros1), np.random.default_rng(5)
    t = ts.types
    frames = ["", "a", "ab", "abc", "imu", "imu_link", "a_longer_frame_id"] * 3
    values = rng.standard_normal((len(frames), 16))
    serialize = ts.serialize_ros1 if ros1 else ts.serialize_cdr
    raws = {MAG: [], IMU: [], FIX: []}
    for k, (frame, v) in enumerate(zip(frames, values)):
        stamp = t["builtin_interfaces/msg/Time"](sec=k, nanosec=1000 * k)
        header = t["std_msgs/msg/Header"](**({"seq": k} if ros1 else {}), stamp=stamp, frame_id=frame)
        v3 = lambda x: t["geometry_msgs/msg/Vector3"](x=x[0], y=x[1], z=x[2])  # noqa: E731
        raws[MAG].append(bytes(serialize(t[MAG](header=header, magnetic_field=v3(v[:3]), magnetic_field_covariance=np.zeros(9)), MAG)))
        raws[IMU].append(bytes(serialize(t[IMU](
            header=header, orientation=t["geometry_msgs/msg/Quaternion"](x=v[3], y=v[4], z=v[5], w=v[6]),
            orientation_covariance=np.full(9, v[7]), angular_velocity=v3(v[8:11]), angular_velocity_covariance=np.zeros(9),
            linear_acceleration=v3(v[11:14]), linear_acceleration_covariance=np.zeros(9)), IMU)))
        raws[FIX].append(bytes(serialize(t[FIX](
            header=header, status=t["sensor_msgs/msg/NavSatStatus"](status=k % 3 - 1, service=1), latitude=v[14],
            longitude=v[15], altitude=v[0], position_covariance=np.zeros(9), position_covariance_type=k % 4), FIX)))
    received = np.arange(len(frames))
    times, mag = decode(raws[MAG], received, MAG, cdr=not ros1)
    np.testing.assert_array_equal(mag["field"], values[:, :3])
    np.testing.assert_allclose(times, np.arange(len(frames)) * (1 + 1e-6))
    _, imu = decode(raws[IMU], received, IMU, cdr=not ros1)
    np.testing.assert_array_equal(imu["orientation"], values[:, 3:7])
    np.testing.assert_array_equal(imu["orientation_covariance"][:, 0], values[:, 7])
    np.testing.assert_array_equal(imu["angular_velocity"], values[:, 8:11])
    _, fix = decode(raws[FIX], received, FIX, cdr=not ros1)
    np.testing.assert_array_equal(fix["status"][:, 0], np.arange(len(frames)) % 3 - 1)
    np.testing.assert_array_equal(fix["position"], np.column_stack([values[:, 14], values[:, 15], values[:, 0]]))
    for bad in ([raws[MAG][0][:-9]], [raws[MAG][0] + bytes(8)], [raws[FIX][0]]):  # short, long, another type
        with pytest.raises(LayoutError):
            decode(bad, received[:1], MAG, cdr=not ros1)
    if not ros1:  # a DDS payload padded to 4 bytes (NavSatFix ends on one byte) reads the same
        assert decode([raws[FIX][0] + bytes(3)], received[:1], FIX, cdr=True)[1]["position"][0, 0] == values[0, 14]


def test_ros_bag_without_magnetometer_is_one_line(tmp_path):
    from rosbags.rosbag2 import Writer

    ts = typestore(False)
    with Writer(tmp_path / "empty", version=9) as writer:
        writer.add_connection("/gps/fix", "sensor_msgs/msg/NavSatFix", typestore=ts)
    with pytest.raises(MagexpError, match="no sensor_msgs/msg/MagneticField messages") as err:
        load_recording(tmp_path / "empty")
    assert "\n" not in str(err.value)
