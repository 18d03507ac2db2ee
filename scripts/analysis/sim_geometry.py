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
    """Pinhole cameras with radial-tangential distortion (k1 k2 p1 p2, zero on the validation
    family), world-from-camera poses."""

    def __init__(self, ds):
        c = read_cv_yaml(ds + '/config/sim_stereo_imu_config.yaml')
        self.K, self.dist, T_b_c = [], [], []
        for i in range(2):
            cam = read_cv_yaml(ds + f'/config/cam{i}_pinhole.yaml')
            d = cam['distortion_parameters']
            self.K.append(cam['projection_parameters'])
            self.dist.append(np.array([d['k1'], d['k2'], d['p1'], d['p2']], float))
            T_b_c.append(np.array(c[f'body_T_cam{i}']['data']).reshape(4, 4))
        gt_file = ds + '/mav0/state_groundtruth_estimate0/data.csv'
        gt = np.loadtxt(gt_file, delimiter=',', comments='#')
        stamps = np.loadtxt(gt_file, delimiter=',', comments='#', usecols=0, dtype=np.int64)
        self.pose = {}
        for t, r in zip(stamps, gt):
            R_w_b = quat_to_R(*r[4:8])
            self.pose[int(t)] = [(R_w_b @ T[:3, :3], r[1:4] + R_w_b @ T[:3, 3]) for T in T_b_c]

    def distort(self, cam, x, y):
        k1, k2, p1, p2 = self.dist[cam]
        r2 = x * x + y * y
        radial = 1 + k1 * r2 + k2 * r2 * r2
        return (x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
                y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y)

    def project(self, cam, t_ns, p_w):
        """Pixel and depth of world point p_w in camera cam at t_ns."""
        R, p = self.pose[t_ns][cam]
        pc = R.T @ (p_w - p)
        k = self.K[cam]
        x, y = self.distort(cam, pc[0] / pc[2], pc[1] / pc[2])
        return np.array([k['fx'] * x + k['cx'], k['fy'] * y + k['cy']]), pc[2]

    def triangulate(self, t_uv):
        """World point seen at left pixels [(t_ns, (u, v)), ...]: least squares of x × (R^T (X − p)) = 0
        over the observations, with the ground-truth poses."""
        A, b = [], []
        for t, uv in t_uv:
            R, p = self.pose[t][0]
            x = self.normalized(0, uv)
            M = np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]]) @ R.T
            A.append(M)
            b.append(M @ p)
        return np.linalg.lstsq(np.vstack(A), np.concatenate(b), rcond=None)[0]

    def normalized(self, cam, uv):
        """The undistorted normalized ray (x, y, 1) of pixel uv (fixed-point inversion)."""
        k = self.K[cam]
        xd, yd = (uv[0] - k['cx']) / k['fx'], (uv[1] - k['cy']) / k['fy']
        x, y = xd, yd
        for _ in range(20):
            dx, dy = self.distort(cam, x, y)
            x, y = x + xd - dx, y + yd - dy
        return np.array([x, y, 1.0])
