"""Shared by the stereo analyses: a rendered dataset's calibration and ground-truth camera poses."""
import numpy as np
import yaml


def read_cv_yaml(path):
    return yaml.safe_load(open(path).read().replace('%YAML:1.0', '').replace('!!opencv-matrix', ''))


def quat_to_R(w, x, y, z):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


class Rig:
    """Pinhole cameras without distortion (the validation family's), world-from-camera poses."""

    def __init__(self, ds):
        c = read_cv_yaml(ds + '/config/sim_stereo_imu_config.yaml')
        self.K, T_b_c = [], []
        for i in range(2):
            cam = read_cv_yaml(ds + f'/config/cam{i}_pinhole.yaml')
            if any(abs(v) > 1e-12 for v in cam['distortion_parameters'].values()):
                raise SystemExit(f'{ds}/config/cam{i}_pinhole.yaml: distortion is not modelled here, expected zeros')
            self.K.append(cam['projection_parameters'])
            T_b_c.append(np.array(c[f'body_T_cam{i}']['data']).reshape(4, 4))
        gt_file = ds + '/mav0/state_groundtruth_estimate0/data.csv'
        gt = np.loadtxt(gt_file, delimiter=',', comments='#')
        stamps = np.loadtxt(gt_file, delimiter=',', comments='#', usecols=0, dtype=np.int64)
        self.pose = {}
        for t, r in zip(stamps, gt):
            R_w_b = quat_to_R(*r[4:8])
            self.pose[int(t)] = [(R_w_b @ T[:3, :3], r[1:4] + R_w_b @ T[:3, 3]) for T in T_b_c]

    def project(self, cam, t_ns, p_w):
        """Pixel and depth of world point p_w in camera cam at t_ns."""
        R, p = self.pose[t_ns][cam]
        pc = R.T @ (p_w - p)
        k = self.K[cam]
        return np.array([k['fx'] * pc[0] / pc[2] + k['cx'], k['fy'] * pc[1] / pc[2] + k['cy']]), pc[2]

    def normalized(self, cam, uv):
        k = self.K[cam]
        return np.array([(uv[0] - k['cx']) / k['fx'], (uv[1] - k['cy']) / k['fy'], 1.0])
