"""Real calibration files, images and trajectories from public repositories, fetched on first use.

Every file is a byte-identical copy of a blob in a public GitHub repository at a pinned commit
(Kalibr, camera-intrinsic-model-rs, Basalt, rpg_trajectory_evaluation, BoofCV-Data), downloaded with pooch from
``raw.githubusercontent.com`` and checked against its sha256. The data are never committed to this
project: each keeps its repository's licence (the LICENSE files are in the registry too) and the
caveats named in the loaders' docstrings.

A file's name is ``"<repo-name>/<path in that repository>"``, e.g. ``"basalt/data/tumvi_512_eucm_calib.json"``,
and it is stored under that same relative path in the data folder: the folder named by the environment variable
``GPO_DATA_DIR``, else the ``datasets`` folder of gpo's cache (``gpo.io.cache``). Point ``GPO_DATA_DIR`` at a folder
that already holds copies in this layout and nothing is downloaded (CI points it at ``../shared/real_data`` to work
offline).
"""

import difflib
import importlib.util
import os
from pathlib import Path

import cv2
import numpy as np
import pooch

from gpo.io import cache

#: repository folder name -> (GitHub owner/repository, pinned commit)
_REPOSITORIES = {
    "kalibr": ("ethz-asl/kalibr", "1f60227442d25e36365ef5f72cd80b9666d73467"),
    "camera-intrinsic-model-rs": ("powei-lin/camera-intrinsic-model-rs", "f723eb8316da0858ceecf3db257d7c5992f6aeed"),
    "basalt": ("VladyslavUsenko/basalt", "0f3b2b52c807f70ff4e2973ce253c73329eea7bc"),
    "rpg_trajectory_evaluation": ("uzh-rpg/rpg_trajectory_evaluation", "8c8ceec55c5c5094a6494208cfc5f54afe0bbc4d"),
    "boofcv-data": ("lessthanoptimal/BoofCV-Data", "cc6d8adf795be2e0c6cc12b42b9ed0c92cab0fcf"),
}

_KALIBR_EXAMPLE = "kalibr/aslam_cv/aslam_cv_python/example"
_TUM = "camera-intrinsic-model-rs/data"
_RPG_RUN = "rpg_trajectory_evaluation/results/euroc_vislam_mono/laptop/vislam_ba/laptop_vislam_ba_V1_02"
_BOOFCV_FISHEYE = "boofcv-data/example/calibration/fisheye/chessboard"
_BOOFCV_VIEWS = 26

#: file name -> sha256
_SHA256 = {
    "kalibr/LICENSE": "1181b1c28fecb9348995fa731e50e36bbe6255660f7554831f8a87f65c9d5b09",
    "kalibr/aslam_cv/aslam_cameras/test/testImageCheckerboard.jpg": (
        "834b273607d248f4d032d891781a980c3f5ddc1fb5c5c8114753b3338c612611"
    ),
    f"{_KALIBR_EXAMPLE}/im_front.jpg": "416302be5ff9d4c46dbd99d4b9d8256599e8d21bea99e934a5f7e6cb642e70cf",
    f"{_KALIBR_EXAMPLE}/im_left.jpg": "79fbc35d425041060311a2a95787bbd37b6990cd054b5e190774a052f63020cf",
    f"{_KALIBR_EXAMPLE}/im_rear.jpg": "f77fc3ef3e033c812bcd93662792a194ef4788e7026d67610f2f60ca4f2455db",
    f"{_KALIBR_EXAMPLE}/im_right.jpg": "95a03d2d9371a6f09072e22ff1001143966a90f49b2d44bd5632d3154e782651",
    f"{_KALIBR_EXAMPLE}/pipeline.info": "820528eef40575a63e3039f8380b82fbd2e724a69ffb9507af0156995e76bfc9",
    "camera-intrinsic-model-rs/LICENSE": "c71d239df91726fc519c6eb72d318ec65820627232b2f796219e87dcf35d0ab4",
    f"{_TUM}/cam0.png": "d36e2a660918b1b5eec678904b43bcd7e39200d207bdf33ab0a630c9901fc14b",
    f"{_TUM}/cam1.png": "1be738c1c27e2d2388dff154eeb251a6e70dfea74d77cf3a2983a8fd331dcab1",
    f"{_TUM}/eucm0.json": "ab1bb63f33875baf3bfcb45809ab601fe264f87743c685aed1e6601d0200e40d",
    f"{_TUM}/eucm1.json": "a2cc310e99537f385867a545cc47395bb3dace7a57d1912bf29bad9b56fa574f",
    f"{_TUM}/fov_tum_mono.json": "484c2ecd37faed9c074f373d37e4396b10f4e674eeea3ba200635a597c839a89",
    f"{_TUM}/fov_tum_mono.png": "59b3704363442cc13ced22aa86368d6623d09a76a70980d0806cca76d4aa33e6",
    f"{_TUM}/tum_vi_with_chart.png": "ec2dec03a1efa960102f36fe2da8a2c4b82d5ba8e8a814fc267b2972fc0bc342",
    "basalt/LICENSE": "8abbeeb535841bbf306a006b54b5829974156abd98a68f6398558db43a51dd0c",
    "basalt/data/aprilgrid_6x6.json": "ef4728769502d27e647b2da5e550ce3d2102aaf76209ff14343d80c5029728f9",
    "basalt/data/euroc_ds_calib.json": "ad8c5a18c48c55dacf61d18ebbc18cd7d4f3acccd5840bd5a5cd8646adb6271c",
    "basalt/data/euroc_eucm_calib.json": "f1f9b0b63726df8d7b56bb315f21b8beaca5493a7e0de95d0f25a5b500d247cd",
    "basalt/data/t265_kb4_calib.json": "42c85500728df62a3fc757efa412a7b0a4dfe26c34c8dd23bbe27b0ec9e01330",
    "basalt/data/tumvi_512_ds_calib.json": "6286c43a43b2cce8f4c3974765106a8da13c357b888d4a5c44f085616e96a04c",
    "basalt/data/tumvi_512_eucm_calib.json": "740382dcf55dc5b0a411aa3f1cca5c090028d09f83b02569029ca174d4d1f85b",
    "rpg_trajectory_evaluation/LICENSE": "5fbbb4067a768276cb40e80ceb6664c206f042fa2fe5b77a6754f4fa2fa71638",
    f"{_RPG_RUN}/eval_cfg.yaml": "54b314ad55b130f861f6b944d7aa8ab8e1a8f39c724a5af9ad8a6a00d4dfe84a",
    f"{_RPG_RUN}/stamped_ba_estimate0.txt": "18e4016ca37252f025b01a9b79b0626bdd90ead94f66affd992f0faa551464f2",
    f"{_RPG_RUN}/stamped_groundtruth.txt": "5df27c489c31dba45a493ce95a15dfe48f1ed6b490cdaf0b3ff66f1cdd9d4977",
    "boofcv-data/LICENSE.TXT": "dd22e752ddef5d6a1738fdbda73aeb074a1464269fb166ee99e5e9f4bf2cb7b6",
    f"{_BOOFCV_FISHEYE}/1.jpg": "ddfbddadf20758a9e323025ab9476e7e77fa7f5dbcd6c06f9146efb1ac4f57bb",
    f"{_BOOFCV_FISHEYE}/2.jpg": "6ec2dab115fb43acd02f4f85a7f3df56fc1fe247f46479a67e654c1f9a9f6cdf",
    f"{_BOOFCV_FISHEYE}/3.jpg": "b2039d029b812403b4598691064c342ac1f7012de1f8e9924e412639e84ef72d",
    f"{_BOOFCV_FISHEYE}/4.jpg": "e4fd46708f31bb891b184d51c70cb438471907cac2fbabce2f687b449fd1fc90",
    f"{_BOOFCV_FISHEYE}/5.jpg": "1e031a07255a7d31de47e4a49fcf15a98bc9bf562a5febe3cdbc8c9eabf7291e",
    f"{_BOOFCV_FISHEYE}/6.jpg": "84e8e74d5a6a4dfa16b6571a8f18b1b0a4bd9892f5b87ed5d28b11c5a7406ee8",
    f"{_BOOFCV_FISHEYE}/7.jpg": "8cb2d46c62b33bc3a1d1002123570869a4a9e5f8f6d3fc917b2650fe31acee93",
    f"{_BOOFCV_FISHEYE}/8.jpg": "c6a38bf3a30c73ace80e1d8171a151124cbc03523b9b3429f1267d5228d06fca",
    f"{_BOOFCV_FISHEYE}/9.jpg": "858154368363658d6f2d6c4471c2fc51911ac5669082d8a705c9aa171115fe75",
    f"{_BOOFCV_FISHEYE}/10.jpg": "c9594d74d9d86cd1a7b53aa2c8bf075c90fb90453a8d81c28060b7a6850d2540",
    f"{_BOOFCV_FISHEYE}/11.jpg": "06b9d1aa1ca776eb20df894e10c1152d133e81397f068d6172fcceb4a56de4c3",
    f"{_BOOFCV_FISHEYE}/12.jpg": "90724aadfc95a7495366640dfd81dcd9abbc2c81c3cd3bf6d500ce75c5ef654f",
    f"{_BOOFCV_FISHEYE}/13.jpg": "179854d7f747a7403cddba51ef0a5be7dcd5a58ceab4adcfe8768d9debeb5046",
    f"{_BOOFCV_FISHEYE}/14.jpg": "584046abbc840eb82fbd2f86678c80b3e0f37d5cd6bd29b2c2a67d5224bf67a3",
    f"{_BOOFCV_FISHEYE}/15.jpg": "bb37b812b7cb171003f9f8b0d4da4961535c18b40b130b49afddea69469fd25e",
    f"{_BOOFCV_FISHEYE}/16.jpg": "63550494114a13049885c1e63fe56bd53022fb1884e569d865fd8d30fe0fad37",
    f"{_BOOFCV_FISHEYE}/17.jpg": "0471fe12edc020b047d1d5fdc136d4358e3f1b6f24e4236eea168195c89f2570",
    f"{_BOOFCV_FISHEYE}/18.jpg": "60699797ed22f4fceb7741c1058a2b038409575c69c5f654b721b66f94587a94",
    f"{_BOOFCV_FISHEYE}/19.jpg": "919d2d548547bffc8e11f66aaca8fe65b6cb28626c14cb907d5c1d30e55b1bf9",
    f"{_BOOFCV_FISHEYE}/20.jpg": "8b675514b19e7676f6cbb1f7f0f0740385b9e93c560568e110608ca1a318f24c",
    f"{_BOOFCV_FISHEYE}/21.jpg": "5acfca6a1feee1c7cb061f2dac69e9658ba6299713e64836a2ad4333b1fcfb98",
    f"{_BOOFCV_FISHEYE}/22.jpg": "286973dbf2360bb80f8660f063c059929bf54c723a1c26b44a552bcc7b77d547",
    f"{_BOOFCV_FISHEYE}/23.jpg": "5f279045c94c866954f388c0f2d9a1a48350f05cdf961069bc0e37dc49354fbd",
    f"{_BOOFCV_FISHEYE}/24.jpg": "d96db5fab235655609b38b813166dfa82085edfd69f595ad3394a4692112564b",
    f"{_BOOFCV_FISHEYE}/25.jpg": "4ae51e8317923154412dd3099908158cdcc5846d37677e2c9076cb5b0ba9fbbe",
    f"{_BOOFCV_FISHEYE}/26.jpg": "9d5dfecf5e05e9331d395efee4e9d70c55ceb78b5b86b80f4e5521b9ecfd68ca",
    f"{_BOOFCV_FISHEYE}/calibration_target.yaml": "178a03f1a9868f634ef5f4604ed8105e3f5eab936e32bf3670e7adbfa4725c03",
    f"{_BOOFCV_FISHEYE}/fisheye.yaml": "ade9f737bd2d263f022e7c5e67e0cb648b7d24dd4e4f453accdd26577cc33fc7",
}

_TIMEOUT_S = 30


class DatasetUnavailable(RuntimeError):
    """A registered file is neither in the data folder nor downloadable (no network, wrong hash, no write access)."""


def _url(name: str) -> str:
    """The raw GitHub URL of a registered file at its repository's pinned commit."""
    folder, _, path = name.partition("/")
    repository, commit = _REPOSITORIES[folder]
    return f"https://raw.githubusercontent.com/{repository}/{commit}/{path}"


def names() -> list[str]:
    """Every registered file name, ``"<repo-name>/<path>"``, sorted."""
    return sorted(_SHA256)


def _close_matches(name: str) -> list[str]:
    """Registered names like ``name``: comparing whole names, else the file names alone."""
    close = difflib.get_close_matches(name, names(), n=3, cutoff=0.5)
    if not close:
        files = difflib.get_close_matches(Path(name).name, [Path(key).name for key in names()], n=3)
        close = [key for key in names() if Path(key).name in files]
    return close


def data_dir() -> Path:
    """The folder of the real files: ``$GPO_DATA_DIR`` when set, else the ``datasets`` folder of gpo's cache."""
    data = os.environ.get("GPO_DATA_DIR")
    return Path(data).expanduser() if data else cache.folder("datasets")


def fetch(name: str) -> Path:
    """The local path of the registered file ``name``, downloaded (and sha256-checked) on first use.

    Raises KeyError for a name not in the registry (naming the closest ones), and `DatasetUnavailable`
    when the file is not in the data folder and cannot be downloaded.
    """
    if name not in _SHA256:
        close = _close_matches(name)
        hint = f"did you mean {', '.join(map(repr, close))}?" if close else "see gpo.io.datasets.names()"
        raise KeyError(f"{name!r} is not a gpo dataset file; {hint}")
    folder = data_dir()
    store = pooch.Pooch(
        path=folder,
        base_url="",
        registry={key: f"sha256:{value}" for key, value in _SHA256.items()},
        urls={key: _url(key) for key in _SHA256},
    )
    downloader = pooch.HTTPDownloader(timeout=_TIMEOUT_S, progressbar=importlib.util.find_spec("tqdm") is not None)
    try:
        return Path(store.fetch(name, downloader=downloader))
    except (OSError, ValueError) as error:  # requests' errors are OSErrors; pooch's hash mismatch is a ValueError
        raise DatasetUnavailable(
            f"{name}: no valid copy in the data folder {folder}, and the download from {_url(name)} failed ({error}). "
            "Set GPO_DATA_DIR to a folder holding a copy as <repo-name>/<path> (e.g. ../shared/real_data), "
            "or connect to the internet and try again."
        ) from error


def tumvi_eucm_calibration() -> Path:
    """Basalt's published EUCM calibration of the TUM VI 512x512 stereo rig (JSON; cam0 and cam1).

    From VladyslavUsenko/basalt (BSD-3-Clause); read it with `gpo.cameras.files.load_basalt`.
    """
    return fetch("basalt/data/tumvi_512_eucm_calib.json")


def tumvi_chart_image() -> np.ndarray:
    """A 512x512 TUM VI fisheye frame showing a calibration chart, as a uint8 grey image.

    The PNG holds 16-bit values (up to 65520); the 8-bit image is ``value // 256``, i.e. the top 8 bits,
    without any contrast stretch. Which TUM VI camera took it is not verified (probably cam0, see
    `tumvi_eucm_calibration`). From powei-lin/camera-intrinsic-model-rs (Apache-2.0); the frame is from the
    TUM VI dataset, which TUM lists under CC BY 4.0: check this before redistributing, and cite the TUM paper.
    """
    image = cv2.imread(str(fetch(f"{_TUM}/tum_vi_with_chart.png")), cv2.IMREAD_UNCHANGED)
    return (image >> 8).astype(np.uint8)


def kalibr_car_images() -> dict[str, np.ndarray]:
    """The four 1280x800 uint8 grey surround-view fisheye images of Kalibr's car example, by camera.

    Keys ``front``, ``left``, ``rear``, ``right``: low-mounted fisheye cameras of the V-Charge car "grobi"
    (ETH ASL, May 2013) looking at asphalt with lane markings. Their intrinsics and camera-to-vehicle
    extrinsics are in `kalibr_car_pipeline_info`. From ethz-asl/kalibr (BSD-3-Clause).
    """
    return {
        camera: cv2.imread(str(fetch(f"{_KALIBR_EXAMPLE}/im_{camera}.jpg")), cv2.IMREAD_GRAYSCALE)
        for camera in ("front", "left", "rear", "right")
    }


def kalibr_car_pipeline_info() -> Path:
    """The path of Kalibr's ``pipeline.info`` for the car images (boost property-tree INFO format).

    Per camera: Mei/unified "omni" intrinsics (xi, fu, fv, cu, cv) with radtan distortion, and ``T_v_c``
    extrinsics whose quaternions follow the JPL convention (R_vc = R_hamilton(q)^T; read literally as
    Hamilton they give nonsense axes). From ethz-asl/kalibr (BSD-3-Clause).
    """
    return fetch(f"{_KALIBR_EXAMPLE}/pipeline.info")


def floor_checkerboard_image() -> np.ndarray:
    """A 1280x960 uint8 grey fisheye-like image looking down at a checkerboard lying on the floor.

    9x10 squares, so 8x9 inner corners; Kalibr's test assumes 0.05 m spacing, the real square size is not
    verified, and no intrinsics are published for it. From ethz-asl/kalibr (BSD-3-Clause).
    """
    return cv2.imread(str(fetch("kalibr/aslam_cv/aslam_cameras/test/testImageCheckerboard.jpg")), cv2.IMREAD_GRAYSCALE)


def rpg_trajectories() -> dict[str, Path]:
    """Paths of one EuRoC V1_02 run from rpg_trajectory_evaluation (MIT): ``estimate``, ``groundtruth``, ``eval_cfg``.

    The estimate is a VI-SLAM (BA) result and the ground truth is EuRoC's, both TUM-format text files
    (``# timestamp tx ty tz qx qy qz qw``); ``eval_cfg.yaml`` asks for ``posyaw`` alignment over all frames.
    """
    return {
        "estimate": fetch(f"{_RPG_RUN}/stamped_ba_estimate0.txt"),
        "groundtruth": fetch(f"{_RPG_RUN}/stamped_groundtruth.txt"),
        "eval_cfg": fetch(f"{_RPG_RUN}/eval_cfg.yaml"),
    }


def boofcv_fisheye_chessboard() -> tuple[list[Path], Path]:
    """26 real fisheye views of a chessboard and BoofCV's own calibration of them: (image paths, ``fisheye.yaml``).

    640 x 720 colour JPEGs of a board of 7 x 5 squares, i.e. 6 x 4 inner corners (the square size is not
    published: lengths come out in squares). ``fisheye.yaml`` holds BoofCV's unified (Mei) model with two
    radial and two tangential coefficients (``omnidirectional_universal``); read it with
    `gpo.cameras.files.load_boofcv`. From lessthanoptimal/BoofCV-Data, CC BY 4.0, (c) Peter Abeles: attribute BoofCV.
    """
    images = [fetch(f"{_BOOFCV_FISHEYE}/{index}.jpg") for index in range(1, _BOOFCV_VIEWS + 1)]
    return images, fetch(f"{_BOOFCV_FISHEYE}/fisheye.yaml")
