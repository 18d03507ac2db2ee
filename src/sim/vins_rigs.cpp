#include "sim/vins_rigs.h"

namespace idyvins::sim {

namespace {

// Read off VINS-Fusion's config/ folder: config and camera files' numbers, nothing else.
// Each camera file and mount once; the configs sharing them name them.
const VinsCamera kEurocCam0 = {"cam0_mei.yaml",
                               true,
                               752,
                               480,
                               3.6313355285286337,
                               {2138.7619122017772, 2131.5886210259278, 361.198566332638, 248.27644773395667},
                               {1.1757726639872075, 15.491281051140213, -0.0008123717295455049, 0.0006729768403031024}};
const VinsCamera kEurocCam1 = {
    "cam1_mei.yaml",
    true,
    752,
    480,
    0.8126150589414611,
    {834.0624973543779, 831.4060676591695, 374.3200735524974, 254.22391621480082},
    {-0.34247886078397966, 0.17108792755973357, -0.0006665314436490669, 0.0007231125584676709}};
const VinsCamera kA3Cam0 = {"left.yaml",
                            false,
                            640,
                            512,
                            0.0,
                            {443.6476851702351, 443.83960982739706, 318.7128184842236, 249.90737366327537},
                            {-0.13445051055717713, 0.0933524405900592, 1.984960914317431e-05, -0.00022312866795141505}};
const VinsCamera kA3Cam1 = {"right.yaml",
                            false,
                            640,
                            512,
                            0.0,
                            {445.4806441513655, 446.1529803431143, 318.1934040190453, 250.04333891088854},
                            {-0.1350808344962313, 0.09272783438007862, -2.032382411100716e-06, 0.0002617509493130587}};
const VinsCamera kMynteyeCam0 = {
    "left_mei.yaml",
    true,
    752,
    480,
    1.4456544769803834,
    {895.9437186180799, 897.4158147903275, 372.21680816143993, 238.33534175557006},
    {-0.3436305335767336, 0.062347376791548004, 0.0012608078788285675, -0.00021374139252651483}};
const VinsCamera kMynteyeCam1 = {
    "right_mei.yaml",
    true,
    752,
    480,
    1.505603054067246,
    {917.5019524357847, 918.8684207772844, 362.8357228085606, 247.89274770430072},
    {-0.3343868800161346, 0.059476752495134476, 0.0008097782762384097, -0.00030586511092468437}};
const VinsCamera kRealsenseCam0 = {"left.yaml",
                                   false,
                                   640,
                                   480,
                                   0.0,
                                   {385.7544860839844, 385.7544860839844, 323.1204833984375, 236.7432098388672},
                                   {0.0, 0.0, 0.0, 0.0}};
const VinsCamera kRealsenseCam1 = {"right.yaml",
                                   false,
                                   640,
                                   480,
                                   0.0,
                                   {385.7544860839844, 385.7544860839844, 323.1204833984375, 236.7432098388672},
                                   {0.0, 0.0, 0.0, 0.0}};
const VinsCamera kKittiOdom0002Cam0 = {
    "cam00-02.yaml", false, 1241, 376, 0.0, {718.856, 718.856, 607.1928, 185.2157}, {0.0, 0.0, 0.0, 0.0}};
const VinsCamera kKittiOdom03Cam0 = {
    "cam03.yaml", false, 1241, 376, 0.0, {721.5377, 721.5377, 609.5593, 172.854}, {0.0, 0.0, 0.0, 0.0}};
const VinsCamera kKittiOdom0412Cam0 = {
    "cam04-12.yaml", false, 1241, 376, 0.0, {707.0912, 707.0912, 601.8873, 183.1104}, {0.0, 0.0, 0.0, 0.0}};
const VinsCamera kKittiOdom1321Cam0 = {
    "cam13-21.yaml", false, 1241, 376, 0.0, {718.856, 718.856, 607.1928, 185.2157}, {0.0, 0.0, 0.0, 0.0}};
const VinsCamera kKittiRaw0930Cam0 = {
    "cam_09_30.yaml", false, 1226, 370, 0.0, {707.0912, 707.0912, 601.8873, 183.1104}, {0.0, 0.0, 0.0, 0.0}};
const VinsCamera kKittiRaw1003Cam0 = {
    "cam_10_03.yaml", false, 1241, 376, 0.0, {718.856, 718.856, 607.1928, 185.2157}, {0.0, 0.0, 0.0, 0.0}};
const VinsCamera kViCarCam0 = {
    "cam0_mei.yaml",
    true,
    752,
    480,
    1.81628169046974,
    {1321.779292128952, 1323.7233061481388, 352.63371410695777, 229.6871696602213},
    {-0.0522809669380076, 0.5370950185713779, -0.00035867321540317175, -0.000255968381366041}};
const VinsCamera kViCarCam1 = {"cam1_mei.yaml",
                               true,
                               752,
                               480,
                               1.0717101664076085,
                               {970.6884495711722, 972.1326760800629, 382.7853925573185, 214.9586602978924},
                               {-0.3022127979126049, 0.196474998960327, 0.0001664773886880363, 0.0005133231550042812}};
const VinsCamera kSimulationCam0 = {
    "cam0_mei.yaml",
    true,
    752,
    480,
    3.06337649174255,
    {1877.332891282959, 1871.3578182686983, 361.4667281280348, 248.25977260132368},
    {0.6729612508720237, 7.0505005635804165, -0.000716464170601934, 3.7726282314036e-06}};
const VinsCamera kSimulationCam1 = {
    "cam1_mei.yaml",
    true,
    752,
    480,
    0.7954312931543704,
    {826.3725324437398, 823.8149817350328, 374.51475162974936, 254.1855932520804},
    {-0.34301744493890163, 0.16523345829809358, -0.0006639028922472272, 0.0006101382116234798}};
const VinsMount kEurocMount0 = {{0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975, 0.999557249008,
                                 0.0149672133247, 0.025715529948, -0.064676986768, -0.0257744366974, 0.00375618835797,
                                 0.999660727178, 0.00981073058949}};
const VinsMount kEurocMount1 = {{0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556, 0.999598781151,
                                 0.0130119051815, 0.0251588363115, 0.0453689425024, -0.0253898008918, 0.0179005838253,
                                 0.999517347078, 0.00786212447038}};
const VinsMount kA3Mount0 = {{-0.026001622181574202, -0.00520858729097301, -0.9996483312957406, -0.12886997952961168,
                              0.9996548156677538, 0.0036294078574090616, -0.026020701583033656, -0.12147595522352593,
                              0.0037636626038181076, -0.999979848805483, 0.005112418876396019, 0.03288156119127258}};
const VinsMount kA3Mount1 = {{-0.023877053002065107, -0.012793564889566844, -0.9996330381881908, -0.1069652669520982,
                              0.9996804853967111, 0.007991524653214732, -0.02398046393865988, 0.0038910400198456374,
                              0.00829538769033017, -0.9998862236430373, 0.012598663101044294, 0.03195626820511115}};
const VinsMount kA3Mount02 = {{-0.03371123984693836, 0.0055879405352924905, -0.9994159930822382, -0.13488097324114276,
                               0.9994310361035674, 0.0012644297085154799, -0.033704677575404185, -0.11681178648179885,
                               0.001075351538766256, -0.9999835879343653, -0.005627386692045988, 0.041641064011355096}};
const VinsMount kA3Mount12 = {{-0.025349732839191397, 0.0008655714765239408, -0.9996782691601336, -0.12784802722835098,
                               0.9996722143305303, 0.0036084788347405805, -0.025346454899911497, 0.002293503190210403,
                               0.003585378707422038, -0.9999931148095561, -0.0009567617290144881,
                               0.041243006399912775}};
const VinsMount kMynteyeMount0 = {{0.004281244149002439, -0.9999700150747368, -0.0064528985710044385,
                                   5.258335607158979e-05, 0.9999690093573452, 0.004238427061257655,
                                   0.006634460108875743, -0.04217470654416256, -0.006606911035158319,
                                   -0.006481102335053651, 0.9999571711023908, 0.019238715201769417}};
const VinsMount kMynteyeMount1 = {{0.0016525177162010074, -0.9999850985367248, -0.005203065413275529,
                                   -0.0029251875934051923, 0.9999493539385108, 0.0016007594247438028,
                                   0.009936152536021484, 0.07437906173155072, -0.009927675616811509,
                                   -0.005219221566601328, 0.9999370985132445, 0.019302672329335892}};
const VinsMount kRealsenseMount0 = {{-0.005758630585728675, -0.004046331878772902, 0.9999752323793346,
                                     0.0203292679503559, -0.9999828721416042, -0.0010224590553211677,
                                     -0.005762811892528363, 0.007932520963961565, 0.001045751980915166,
                                     -0.9999912908499791, -0.0040403746097850135, 0.002855982464514802}};
const VinsMount kRealsenseMount1 = {{-0.0010021770212322867, 0.0003631348032273052, 0.9999994318870054,
                                     0.015285779565991807, -0.999992163429265, -0.003830342261592401,
                                     -0.0010007788055728661, -0.052435791444330505, 0.0038299766679101843,
                                     -0.9999925982782445, 0.0003669706384934468, 0.008693130245019906}};
const VinsMount kKittiOdom0002Mount0 = {{1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0}};
const VinsMount kKittiOdom0002Mount1 = {{1.0, 0.0, 0.0, 0.537165718864418, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0}};
const VinsMount kKittiOdom03Mount1 = {{1.0, 0.0, 0.0, 0.537150588250621, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0}};
const VinsMount kKittiOdom0412Mount1 = {{1.0, 0.0, 0.0, 0.537150653267924, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0}};
const VinsMount kViCarMount0 = {{0.9999103658295864, 0.01194879307051136, -0.006040418089906158, 0.03883692512960596,
                                 -0.011931508793228868, 0.9999246423307501, 0.0028894216789357523,
                                 -0.004740682351846409, 0.00607448799981266, -0.002817091386466092, 0.9999775820445479,
                                 -0.003599770282272336}};
const VinsMount kViCarMount1 = {{0.9999352499616789, 0.010794248206017055, 0.0036027891614088276, -0.07183110963700214,
                                 -0.010796833045707175, 0.9999414683398061, 0.0006987779445089286,
                                 0.00021952350924807923, -0.0035950355016039623, -0.0007376314116848582,
                                 0.9999932657871465, -0.007195280031457313}};
const VinsMount kSimulationMount0 = {{0.0, 0.0, -1.0, -0.02, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.02}};
const VinsMount kSimulationMount1 = {{0.0, 0.0, -1.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.3}};

const std::vector<VinsRig> kRigs = {
    {"euroc_mono_imu",
     "euroc_mono_imu_config.yaml",
     1,
     true,
     752,
     480,
     {kEurocCam0, kEurocCam1},
     {kEurocMount0, kEurocMount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81007},
     0,
     0,
     150,
     30.0,
     1,
     20,
     200},
    {"euroc_stereo",
     "euroc_stereo_config.yaml",
     2,
     false,
     752,
     480,
     {kEurocCam0, kEurocCam1},
     {kEurocMount0, kEurocMount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81},
     0,
     0,
     150,
     30.0,
     1,
     20,
     200},
    {"euroc_stereo_imu",
     "euroc_stereo_imu_config.yaml",
     2,
     true,
     752,
     480,
     {kEurocCam0, kEurocCam1},
     {kEurocMount0, kEurocMount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81007},
     0,
     0,
     150,
     30.0,
     1,
     20,
     200},
    {"a3_ptgrey_mono_imu",
     "a3_ptgrey_mono_imu_config.yaml",
     1,
     true,
     640,
     512,
     {kA3Cam0, kA3Cam1},
     {kA3Mount0, kA3Mount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81},
     0,
     1,
     150,
     30.0,
     1,
     20,
     400},
    {"a3_ptgrey_stereo",
     "a3_ptgrey_stereo_config.yaml",
     2,
     false,
     640,
     512,
     {kA3Cam0, kA3Cam1},
     {kA3Mount0, kA3Mount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81},
     0,
     0,
     150,
     30.0,
     1,
     20,
     400},
    {"a3_ptgrey_stereo_imu",
     "a3_ptgrey_stereo_imu_config.yaml",
     2,
     true,
     640,
     512,
     {kA3Cam0, kA3Cam1},
     {kA3Mount02, kA3Mount12},
     {0.1, 0.01, 0.001, 0.0001, 9.81},
     1,
     1,
     150,
     30.0,
     1,
     20,
     400},
    {"mynteye_mono_imu",
     "mynteye_mono_imu_config.yaml",
     1,
     true,
     752,
     480,
     {kMynteyeCam0, kMynteyeCam1},
     {kMynteyeMount0, kMynteyeMount1},
     {0.1, 0.01, 0.001, 0.0001, 9.8},
     1,
     0,
     150,
     30.0,
     1,
     30,
     200},
    {"mynteye_stereo",
     "mynteye_stereo_config.yaml",
     2,
     false,
     752,
     480,
     {kMynteyeCam0, kMynteyeCam1},
     {kMynteyeMount0, kMynteyeMount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81},
     0,
     0,
     150,
     30.0,
     1,
     30,
     200},
    {"mynteye_stereo_imu",
     "mynteye_stereo_imu_config.yaml",
     2,
     true,
     752,
     480,
     {kMynteyeCam0, kMynteyeCam1},
     {kMynteyeMount0, kMynteyeMount1},
     {0.01, 0.001, 0.0001, 1e-05, 9.8},
     0,
     0,
     150,
     30.0,
     1,
     30,
     200},
    {"realsense_stereo_imu",
     "realsense_stereo_imu_config.yaml",
     2,
     true,
     640,
     480,
     {kRealsenseCam0, kRealsenseCam1},
     {kRealsenseMount0, kRealsenseMount1},
     {0.1, 0.01, 0.001, 0.0001, 9.805},
     1,
     1,
     150,
     30.0,
     1,
     30,
     200},
    {"kitti_odom_00_02",
     "kitti_config00-02.yaml",
     2,
     false,
     1241,
     376,
     {kKittiOdom0002Cam0, kKittiOdom0002Cam0},
     {kKittiOdom0002Mount0, kKittiOdom0002Mount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81007},
     0,
     0,
     200,
     30.0,
     1,
     10,
     100},
    {"kitti_odom_03",
     "kitti_config03.yaml",
     2,
     false,
     1241,
     376,
     {kKittiOdom03Cam0, kKittiOdom03Cam0},
     {kKittiOdom0002Mount0, kKittiOdom03Mount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81007},
     0,
     0,
     200,
     30.0,
     1,
     10,
     100},
    {"kitti_odom_04_12",
     "kitti_config04-12.yaml",
     2,
     false,
     1241,
     376,
     {kKittiOdom0412Cam0, kKittiOdom0412Cam0},
     {kKittiOdom0002Mount0, kKittiOdom0412Mount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81007},
     0,
     0,
     200,
     30.0,
     1,
     10,
     100},
    {"kitti_odom_13_21",
     "kitti_config13-21.yaml",
     2,
     false,
     1241,
     376,
     {kKittiOdom1321Cam0, kKittiOdom1321Cam0},
     {kKittiOdom0002Mount0, kKittiOdom0002Mount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81007},
     0,
     0,
     200,
     30.0,
     1,
     10,
     100},
    {"kitti_raw_09_30",
     "kitti_09_30_config.yaml",
     2,
     false,
     1241,
     376,
     {kKittiRaw0930Cam0, kKittiRaw0930Cam0},
     {kKittiOdom0002Mount0, kKittiOdom0412Mount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81007},
     0,
     0,
     200,
     30.0,
     1,
     10,
     100},
    {"kitti_raw_10_03",
     "kitti_10_03_config.yaml",
     2,
     false,
     1241,
     376,
     {kKittiRaw1003Cam0, kKittiRaw1003Cam0},
     {kKittiOdom0002Mount0, kKittiOdom0002Mount1},
     {0.1, 0.01, 0.001, 0.0001, 9.81007},
     0,
     0,
     200,
     30.0,
     1,
     10,
     100},
    {"vi_car",
     "vi_car.yaml",
     2,
     true,
     752,
     480,
     {kViCarCam0, kViCarCam1},
     {kViCarMount0, kViCarMount1},
     {0.1, 0.01, 0.001, 0.0001, 9.8},
     0,
     0,
     150,
     30.0,
     1,
     20,
     200},
    {"simulation",
     "simulation_config.yaml",
     2,
     true,
     600,
     600,
     {kSimulationCam0, kSimulationCam1},
     {kSimulationMount0, kSimulationMount1},
     {0.2, 0.02, 0.0002, 2e-05, 9.805},
     0,
     0,
     150,
     30.0,
     1,
     20,
     200},
};

camera::CameraParams cameraOf(const VinsCamera& v) {
  camera::CameraParams p;
  p.type = v.mei ? camera::ModelType::kMei : camera::ModelType::kPinhole;
  p.name = "camera";
  p.width = v.width;
  p.height = v.height;
  p.xi = v.mei ? v.xi : 0.0;
  p.fx = v.k[0];
  p.fy = v.k[1];
  p.cx = v.k[2];
  p.cy = v.k[3];
  for (int i = 0; i < 4; ++i) p.dist[static_cast<std::size_t>(i)] = v.dist[i];
  return p;
}

}  // namespace

const std::vector<VinsRig>& vinsRigs() { return kRigs; }

const VinsRig* findVinsRig(const std::string& name) {
  for (const VinsRig& r : kRigs)
    if (name == r.name) return &r;
  return nullptr;
}

std::string vinsRigNames() {
  std::string s;
  for (const VinsRig& r : kRigs) s += (s.empty() ? "" : ", ") + std::string(r.name);
  return s;
}

Config vinsRigConfig(const VinsRig& r) {
  Config c;
  c.path = r.config_file;
  c.num_cam = r.num_cam;
  c.use_imu = r.imu;
  c.image_width = r.width;
  c.image_height = r.height;
  for (int i = 0; i < 2; ++i) {
    c.cams.push_back(cameraOf(r.cams[i]));
    c.cam_paths.push_back(r.cams[i].file);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (int k = 0; k < 12; ++k) T.matrix()(k / 4, k % 4) = r.T_b_c[i].m[k];
    c.T_b_c.push_back(T);
  }
  c.imu.noise.acc_n = r.noise[0];
  c.imu.noise.gyr_n = r.noise[1];
  c.imu.noise.acc_w = r.noise[2];
  c.imu.noise.gyr_w = r.noise[3];
  c.imu.noise.g_norm = r.noise[4];
  c.estimator.estimate_extrinsic = r.estimate_extrinsic;
  c.estimator.estimate_td = r.estimate_td != 0;
  c.tracker.max_cnt = r.max_cnt;
  c.tracker.min_dist = r.min_dist;
  c.tracker.flow_back = r.flow_back != 0;
  return c;
}

}  // namespace idyvins::sim
