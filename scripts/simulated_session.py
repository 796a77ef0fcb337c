"""Splits one SIMULATED `errfield simulate` session into training and held-out CSVs, as a user splits a
measured data set: both keep the SIMULATED comment lines, the header and the base rows (one session,
one base-point reading); the first n_train targets train, the rest are held out. Shared by the
measure_*.py scripts."""
import os


def split_session(work, n_train, source="all.csv", train="train.csv", hold="hold.csv"):
    lines = open(os.path.join(work, source)).read().splitlines(True)
    comments = [l for l in lines if l.startswith("#")]
    body = [l for l in lines if not l.startswith("#")]
    base = [l for l in body[1:] if ",base," in l]
    targets = [l for l in body[1:] if ",target," in l]
    open(os.path.join(work, train), "w").writelines(comments + body[:1] + base + targets[:n_train])
    open(os.path.join(work, hold), "w").writelines(comments + body[:1] + base + targets[n_train:])
