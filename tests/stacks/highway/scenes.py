"""A fixed highway-env scene for the tests: the ego in the middle of three lanes closing on a
crawling car 135 m ahead, traffic on both sides. With ``control.ACC_MAX`` at 1.82 m/s^2 it
crashes at 7.2 s; with the defaults it does not."""

from rocas.stacks.highway.scene import scene_from_dict

PLANTED = scene_from_dict({
    "name": "planted", "env": "highway-v0", "duration": 12.0, "frequency": 15.0,
    "config": {"lanes_count": 3},
    "ego": {"lane": "0>1>1", "s": 0.0, "speed": 22.732627709857358,
            "target_speed": 29.022182714629167},
    "others": [
        {"lane": "0>1>1", "s": 135.3497489289001, "speed": 2.484451327578972,
         "lane_change": False},
        {"lane": "0>1>0", "s": 25.0247741206056, "speed": 24.502609440850485,
         "target_speed": 23.520775758499152},
        {"lane": "0>1>0", "s": -26.113696499969432, "speed": 15.938270859440776,
         "target_speed": 14.416425743465256},
        {"lane": "0>1>2", "s": 112.61631493525624, "speed": 19.762853601628457,
         "kind": "linear", "target_speed": 22.24288128147574},
        {"lane": "0>1>2", "s": 100.3775350629262, "speed": 25.470189924019742,
         "kind": "defensive", "target_speed": 25.53178436905198},
    ]})
WEAK_BRAKES = {"control.ACC_MAX": 1.82}
LAZY_LANE_CHANGE = {"planning.LANE_CHANGE_MIN_ACC_GAIN": 2.5}
