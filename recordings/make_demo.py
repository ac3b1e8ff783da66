"""Regenerate recordings/demo/: a scripted accident/reference pair of the built-in channel mix.

Usage: python recordings/make_demo.py
"""

from pathlib import Path

from rocas.recording.synthetic import MixConfig, write_mix_pair

if __name__ == "__main__":
    out = Path(__file__).resolve().parent / "demo"
    out.mkdir(exist_ok=True)
    write_mix_pair(out, MixConfig(duration_s=30.0, seed=0), name="a01_scripted")
    print(f"wrote {out}/a01_scripted_accident.mcap and a01_scripted_reference.mcap")
