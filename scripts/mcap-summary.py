#!/usr/bin/env python3
"""Summarise a snaked recording with Python's mcap package (pip install mcap):
channels (schema, encoding, message count), time span, and the metadata records.

    scripts/mcap-summary.py RUN.mcap [--topic /joints --head 3]

--topic prints the first --head messages of a JSON topic (decoded)."""
import argparse
import json

from mcap.exceptions import McapError
from mcap.reader import make_reader


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("path")
    ap.add_argument("--topic", help="print the first messages of this JSON topic")
    ap.add_argument("--head", type=int, default=3)
    args = ap.parse_args()

    with open(args.path, "rb") as f:
        reader = make_reader(f)
        try:
            summary = reader.get_summary()
        except McapError:  # the end is not a footer: a crash or a full disk cut it
            summary = None
        if summary is None:
            raise SystemExit(
                f"{args.path}: not finished (no summary or footer): "
                f"`snaked --recover {args.path}` makes a finished file of it"
            )
        stats = summary.statistics
        counts = stats.channel_message_counts
        span = (stats.message_end_time - stats.message_start_time) / 1e9
        print(f"{args.path}: {stats.message_count} messages over {span:.3f} s")
        for cid, c in sorted(summary.channels.items(), key=lambda kv: kv[1].topic):
            s = summary.schemas.get(c.schema_id)
            name = f"{s.name} ({s.encoding})" if s else "-"
            print(f"  {c.topic:22} {counts.get(cid, 0):>9}  {name}, {c.message_encoding}")
        for m in reader.iter_metadata():
            print(f"metadata {m.name}:")
            for k, v in sorted(m.metadata.items()):
                print(f"  {k} = {v if len(v) < 200 else v[:200] + '…'}")
        if args.topic:
            for n, (_, _, msg) in enumerate(reader.iter_messages(topics=[args.topic])):
                if n >= args.head:
                    break
                print(json.dumps(json.loads(msg.data)))


if __name__ == "__main__":
    main()
