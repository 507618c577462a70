"""ROS 2 bags as MCAP files, laid out as rosbag2's MCAP storage plugin writes them.

rosbag2 itself is not available as a wheel (ROS 2 comes from PyPI here), so the recorder and
player nodes use this module. The layout follows rosbag2 so that other tools read the files:
profile ``ros2``; one schema per message type, named ``pkg/msg/Type``, encoding ``ros2msg``,
holding the complete definition text (the type's ``.msg`` followed by every nested type's
``.msg``, each after an 80-``=`` line and ``MSG: pkg/msg/Type``); one channel per topic with
message encoding ``cdr`` and the metadata ``offered_qos_profiles`` (YAML) and ``topic_type_hash``.

Message payloads are serialized CDR bytes exactly as received from the middleware. Definitions
are read from the installed ``share/<pkg>/msg/*.msg`` files found on ``AMENT_PREFIX_PATH``
(falling back to this interpreter's prefix).
"""
import functools
import os
import re
import struct
import sys
import time
import zlib
from collections import Counter, namedtuple
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import NonSeekingReader, make_reader
from mcap.writer import CompressionType, Writer
from zstandard import ZstdError

PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"
LIBRARY = "lpa_transfer.recording.bag"
DEFINITION_SEPARATOR = "=" * 80 + "\n"
PRIMITIVE_TYPES = frozenset({
    "bool", "byte", "char", "float32", "float64", "int8", "uint8", "int16", "uint16",
    "int32", "uint32", "int64", "uint64", "string", "wstring"})
HEADER_TYPE = "std_msgs/msg/Header"

TopicInfo = namedtuple("TopicInfo", "type_name message_count offered_qos_profiles")
BagMessage = namedtuple("BagMessage", "topic type_name data log_time_ns publish_time_ns")


class BagError(RuntimeError):
    """A bag file cannot be read or written as asked."""


# ----------------------------------------------------------------------------- definitions

def split_type_name(type_name):
    """``'pkg/msg/Type'`` or ``'pkg/Type'`` -> ``('pkg', 'Type')``."""
    parts = type_name.split("/")
    if len(parts) == 2 or (len(parts) == 3 and parts[1] == "msg"):
        return parts[0], parts[-1]
    raise BagError(f"not a message type name: {type_name!r} (expected pkg/msg/Type)")


def share_prefixes():
    """Install prefixes searched for ``share/<pkg>/msg/<Type>.msg``, in priority order."""
    prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    return prefixes + [sys.prefix]


@functools.lru_cache(maxsize=None)
def msg_file_text(type_name):
    """The installed ``.msg`` text of ``type_name``."""
    package, name = split_type_name(type_name)
    for prefix in share_prefixes():
        path = Path(prefix) / "share" / package / "msg" / f"{name}.msg"
        if path.is_file():
            return path.read_text()
    raise BagError(f"no definition {package}/msg/{name}.msg under share/ of {share_prefixes()}")


def field_lines(msg_text):
    """The lines of a ``.msg`` text that declare a field or constant, comments stripped."""
    lines = (line.split("#", 1)[0].strip() for line in msg_text.splitlines())
    return [line for line in lines if line]


def field_types(msg_text, package):
    """Full names (``pkg/msg/Type``) of the non-primitive field types of one ``.msg``, in order.

    Short names resolve like rosidl does: ``Header`` is ``std_msgs/msg/Header``, any other
    name without a package belongs to ``package``. Constants have primitive types and drop out.
    """
    names = []
    for line in field_lines(msg_text):
        base = re.split(r"[\[<]", line.split()[0], maxsplit=1)[0]  # drop [N], [<=N], <=N
        if base in PRIMITIVE_TYPES:
            continue
        if "/" in base:
            names.append("%s/msg/%s" % split_type_name(base))
        elif base == "Header":
            names.append(HEADER_TYPE)
        else:
            names.append(f"{package}/msg/{base}")
    return names


@functools.lru_cache(maxsize=None)
def message_definition(type_name):
    """The complete ``ros2msg`` definition text of ``type_name`` as stored in a bag's schema.

    As rosbag2 builds it: the type's own text first, then depth-first each not yet included
    dependency (sorted by name), preceded by a newline and the two-line ``MSG:`` delimiter.
    """
    seen = set()

    def with_dependencies(name):
        package, _ = split_type_name(name)
        text = msg_file_text(name)
        for dependency in sorted(set(field_types(text, package))):
            if dependency not in seen:
                seen.add(dependency)
                text += f"\n{DEFINITION_SEPARATOR}MSG: {dependency}\n" + with_dependencies(dependency)
        return text

    return with_dependencies("%s/msg/%s" % split_type_name(type_name))


@functools.lru_cache(maxsize=None)
def starts_with_header(type_name):
    """Whether the first field of ``type_name`` is a ``std_msgs/Header``."""
    package, _ = split_type_name(type_name)
    fields = field_lines(msg_file_text(type_name))
    return bool(fields) and field_types(fields[0], package) == [HEADER_TYPE]


def header_stamp_ns(type_name, cdr):
    """The ``header.stamp`` of a serialized message in ns, or None if it has no leading header.

    CDR: a 4-byte encapsulation header (byte 1 odd = little endian), then the stamp's
    int32 sec and uint32 nanosec as the first fields.
    """
    if len(cdr) < 12 or not starts_with_header(type_name):
        return None
    sec, nanosec = struct.unpack_from("<iI" if cdr[1] & 1 else ">iI", cdr, 4)
    return sec * 1_000_000_000 + nanosec


# ----------------------------------------------------------------------------- QoS metadata

DURATION_INFINITE = {"sec": 9223372036, "nsec": 854775807}


def qos_profiles_yaml(profiles):
    """``offered_qos_profiles`` metadata: a YAML list of QoS dicts as rosbag2 (Jazzy) writes.

    Each profile is a dict with ``history``, ``depth``, ``reliability``, ``durability`` and
    ``liveliness`` (lower-case policy names such as ``keep_last``, ``reliable``); durations
    (``deadline``, ``lifespan``, ``liveliness_lease_duration``) default to infinite.
    """
    lines = []
    for profile in profiles:
        entry = {"history": "keep_last", "depth": 0, "reliability": "reliable",
                 "durability": "volatile", "deadline": DURATION_INFINITE,
                 "lifespan": DURATION_INFINITE, "liveliness": "automatic",
                 "liveliness_lease_duration": DURATION_INFINITE,
                 "avoid_ros_namespace_conventions": False, **profile}
        for index, (key, value) in enumerate(entry.items()):
            lead = "- " if index == 0 else "  "
            if isinstance(value, dict):
                lines.append(f"{lead}{key}:")
                lines += [f"    {k}: {v}" for k, v in value.items()]
            else:
                lines.append(f"{lead}{key}: {str(value).lower() if isinstance(value, bool) else value}")
    return "\n".join(lines) + "\n" if lines else "[]\n"


# ----------------------------------------------------------------------------- writing

class BagWriter:
    """Write one MCAP bag; use as a context manager or call ``close()`` (writes the summary).

    Chunks are zstd-compressed and flushed to the file at least every ``flush_period_s`` while
    messages arrive (and on ``flush()``), so a killed recorder loses little; such a file lacks
    the summary and is only readable with ``read_messages(..., allow_truncated=True)``.
    """

    def __init__(self, path, flush_period_s=1.0, compression=CompressionType.ZSTD):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = open(self.path, "wb")
        self._writer = Writer(self._file, compression=compression)
        self._writer.start(profile=PROFILE, library=LIBRARY)
        self._flush_period_s = flush_period_s
        self._last_flush, self._pending = time.monotonic(), 0
        self._schema_ids = {}
        self._channel_ids = {}
        self.counts = Counter()

    def add_topic(self, topic, type_name, offered_qos_profiles=()):
        """Register ``topic`` with its message type (``pkg/msg/Type``) and offered QoS dicts."""
        if topic in self._channel_ids:
            return
        type_name = "%s/msg/%s" % split_type_name(type_name)
        if type_name not in self._schema_ids:
            self._schema_ids[type_name] = self._writer.register_schema(
                name=type_name, encoding=SCHEMA_ENCODING,
                data=message_definition(type_name).encode())
        self._channel_ids[topic] = self._writer.register_channel(
            topic=topic, message_encoding=MESSAGE_ENCODING, schema_id=self._schema_ids[type_name],
            metadata={"offered_qos_profiles": qos_profiles_yaml(offered_qos_profiles),
                      "topic_type_hash": ""})
        self.counts[topic] = 0

    def write(self, topic, cdr, log_time_ns, publish_time_ns=None):
        """Append one serialized message; ``publish_time_ns`` defaults to ``log_time_ns``."""
        channel_id = self._channel_ids.get(topic)
        if channel_id is None:
            raise BagError(f"topic {topic!r} was not added to {self.path}")
        self._writer.add_message(
            channel_id=channel_id, log_time=log_time_ns, data=bytes(cdr),
            publish_time=log_time_ns if publish_time_ns is None else publish_time_ns,
            sequence=self.counts[topic])
        self.counts[topic] += 1
        self._pending += 1
        if time.monotonic() - self._last_flush > self._flush_period_s:
            self.flush()

    def flush(self):
        """Write the chunk in progress to the file (readable after a kill up to this point)."""
        self._writer.flush()
        self._last_flush, self._pending = time.monotonic(), 0

    def flush_if_due(self):
        """Flush if messages wait and ``flush_period_s`` has passed since the last flush: a
        recorder calls it from a timer, so that a kill loses at most about one period even
        when no further message arrives to trigger the flush in :meth:`write`."""
        if self._pending and time.monotonic() - self._last_flush >= self._flush_period_s:
            self.flush()

    def close(self):
        """Write the summary and footer and close the file; calling it twice is harmless."""
        if self._file.closed:
            return
        try:
            self._writer.finish()
        finally:
            self._file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# ----------------------------------------------------------------------------- reading

#: What a damaged file raises while it is read: mcap's errors (CRC mismatch, bad records),
#: zstd's, the struct/EOF/value errors of a record cut short, and what a corrupt length does.
_READ_ERRORS = (McapError, ZstdError, EOFError, struct.error, ValueError, RuntimeError, KeyError,
                MemoryError, OverflowError)     # (a flipped length field asks for too much)


def _check_summary_crc(stream, path):
    """The footer's CRC of the summary section (chunk and message indexes, statistics): a
    flipped index would send the reader to the wrong chunk without any chunk CRC failing."""
    try:
        size = stream.seek(0, os.SEEK_END)
        if size < 8 + 29 + 8:
            return                                  # too short to be finalised: get_summary says
        stream.seek(size - 8 - 29)                  # the footer record, then the magic
        footer = stream.read(29)
        if footer[0] != 0x02:
            return
        summary_start, _, crc = struct.unpack("<QQI", footer[9:29])
        if crc and 0 < summary_start < size - 8 - 29:
            stream.seek(summary_start)
            covered = stream.read(size - 8 - 29 + 25 - summary_start)
            if zlib.crc32(covered) != crc:
                raise BagError(f"{path}: the summary section (indexes, statistics) fails its "
                               "CRC: the file is damaged")
    finally:
        stream.seek(0)


def _open_reader(stream, path):
    _check_summary_crc(stream, path)
    try:
        reader = make_reader(stream, validate_crcs=True)
    except _READ_ERRORS as error:
        raise BagError(f"{path}: not an MCAP file ({type(error).__name__}: {error})") from None
    try:
        summary = reader.get_summary()
    except _READ_ERRORS as error:
        raise BagError(f"{path}: not a complete MCAP file ({type(error).__name__}: {error}); it "
                       "may be truncated, e.g. by a killed recorder: recover it with "
                       "`python -m lpa_transfer.recording.bag --recover IN OUT`") from error
    if summary is None:
        raise BagError(f"{path}: MCAP file has no summary (not finalised); "
                       "read it with allow_truncated=True")
    if reader.get_header().profile != PROFILE:
        raise BagError(f"{path}: MCAP profile {reader.get_header().profile!r}, expected {PROFILE!r}")
    return reader, summary


def summary(path):
    """``{topic: TopicInfo(type_name, message_count, offered_qos_profiles)}`` of a finished bag."""
    with open(path, "rb") as stream:
        _, info = _open_reader(stream, path)
    counts = info.statistics.channel_message_counts if info.statistics else {}
    return {channel.topic: TopicInfo(info.schemas[channel.schema_id].name,
                                     counts.get(channel_id, 0),
                                     channel.metadata.get("offered_qos_profiles", ""))
            for channel_id, channel in info.channels.items()}


def read_messages(path, topics=None, allow_truncated=False):
    """Yield ``BagMessage(topic, type_name, data, log_time_ns, publish_time_ns)`` in log time order.

    A file without summary (truncated, or its writer was killed) raises ``BagError`` unless
    ``allow_truncated``; then the messages up to the last complete chunk are yielded in file order.
    """
    with open(path, "rb") as stream:
        if allow_truncated:
            yield from _read_truncated(stream, topics)
            return
        reader, info = _open_reader(stream, path)
        ours = reader.get_header().library == LIBRARY
        count, last, sequences = 0, None, Counter()
        try:
            for schema, channel, message in reader.iter_messages(topics=topics,
                                                                 log_time_order=True):
                count, last = count + 1, (channel.topic, message.log_time)
                if ours and message.sequence != sequences[channel.id]:
                    # our writer numbers each topic's messages 0, 1, 2, ... (BagWriter.write)
                    raise BagError(f"{path}: message {sequences[channel.id]} of {channel.topic} "
                                   f"is missing or out of place (read sequence "
                                   f"{message.sequence}): the file is damaged")
                sequences[channel.id] += 1
                yield BagMessage(channel.topic, schema.name, message.data, message.log_time,
                                 message.publish_time)
            expected = info.statistics.channel_message_counts if info.statistics else {}
            short = {info.channels[i].topic: (sequences[i], n) for i, n in expected.items()
                     if ours and (topics is None or info.channels[i].topic in topics)
                     and sequences[i] != n}
            if short:
                raise BagError(f"{path}: messages read per topic differ from the file's "
                               f"statistics (read, recorded): {short}: the file is damaged")
        except _READ_ERRORS as error:
            where = (f"after {count} messages (the last good one on {last[0]} at log time "
                     f"{last[1]} ns)" if last else "before its first message")
            raise BagError(f"{path}: corrupt data {where}, at byte {stream.tell()} of the "
                           f"file: {type(error).__name__}: {error}") from None


def decoded_messages(path, topics=None):
    """Yield ``(topic, log_time_ns, message)`` of a finished bag in log time order, each
    message decoded from its CDR bytes by mcap_ros2 with the definition stored in the file
    (attribute access as the ROS type's fields; no ROS install needed). Checked as
    :func:`read_messages` checks."""
    from mcap_ros2.decoder import DecoderFactory

    with open(path, "rb") as stream:
        _, info = _open_reader(stream, path)
    schemas = {schema.name: schema for schema in info.schemas.values()}
    factory, decoders = DecoderFactory(), {}
    for message in read_messages(path, topics):
        if message.type_name not in decoders:
            decoders[message.type_name] = factory.decoder_for(MESSAGE_ENCODING,
                                                              schemas[message.type_name])
        yield message.topic, message.log_time_ns, decoders[message.type_name](message.data)


def _read_truncated(stream, topics):
    messages = NonSeekingReader(stream, validate_crcs=True).iter_messages(
        topics=topics, log_time_order=False)
    try:
        for schema, channel, message in messages:
            yield BagMessage(channel.topic, schema.name, message.data, message.log_time,
                             message.publish_time)
    except _READ_ERRORS:
        return  # the file ends inside a record: everything complete has been yielded


def describe(path):
    """A ``ros2 bag info``-like text: duration, message counts and types per topic."""
    with open(path, "rb") as stream:
        _, info = _open_reader(stream, path)
    stats = info.statistics
    duration = (stats.message_end_time - stats.message_start_time) * 1e-9 if stats else 0.0
    lines = [f"bag {path}: {stats.message_count if stats else 0} messages over "
             f"{duration:.3f} s (wall clock)"]
    lines += [f"  {topic:<40} {topic_info.message_count:>8}  {topic_info.type_name}"
              for topic, topic_info in sorted(summary(path).items())]
    return "\n".join(lines) + "\n"


def recover(path, output):
    """Write every complete message of a truncated or killed recording at ``path`` into a
    finalised bag at ``output`` (topics, types and offered QoS kept); returns the count."""
    import yaml

    count = 0
    with BagWriter(output) as writer, open(path, "rb") as stream:
        for message in _read_truncated_with_channels(stream):
            schema, channel, record = message
            writer.add_topic(channel.topic, schema.name,
                             yaml.safe_load(channel.metadata.get("offered_qos_profiles") or "[]")
                             or [])
            writer.write(channel.topic, record.data, record.log_time, record.publish_time)
            count += 1
    return count


def _read_truncated_with_channels(stream):
    messages = NonSeekingReader(stream, validate_crcs=True).iter_messages(log_time_order=False)
    try:
        yield from messages
    except _READ_ERRORS:
        return


def main(argv):
    """``python -m lpa_transfer.recording.bag FILE.mcap ...``: the stand-in for ``ros2 bag
    info``; ``--recover IN OUT``: a finalised copy of a killed recording's complete messages."""
    if argv[:1] == ["--recover"]:
        if len(argv) != 3:
            print("usage: python -m lpa_transfer.recording.bag --recover IN OUT", file=sys.stderr)
            return 2
        print(f"recovered {recover(argv[1], argv[2])} messages into {argv[2]}")
        return 0
    for argument in argv:
        try:
            print(describe(argument), end="")
        except (BagError, OSError) as error:
            print(f"error: {error}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
