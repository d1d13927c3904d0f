"""A recording whose attachments were tampered with (rewritten with valid CRCs, so not
"damaged"): the error names the recording and the attachment, with the place inside it.

A recording is data anyone may send. Its `world.yaml` once failed as `default:1:1`
(the world's name in the recording's metadata, a file the user never gave); the
recording is the input at fault, and the attachment is where to look.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from test_replay_support import APPENDIX_C, record
from typer.testing import CliRunner

from aeroexec.cli import app

runner = CliRunner()


def tampered(source: Path, target: Path, name: str, data: bytes) -> Path:
    """A copy of the recording `source` whose attachment `name` holds `data`, written
    by the mcap library (so every CRC is right: tampered, not damaged)."""
    with source.open("rb") as stream, target.open("wb") as out:
        reader = make_reader(stream)
        header = reader.get_header()
        writer = Writer(out)
        writer.start(header.profile, header.library)
        schemas: dict[int, int] = {}
        channels: dict[int, int] = {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if schema is not None and schema.id not in schemas:
                schemas[schema.id] = writer.register_schema(
                    schema.name, schema.encoding, schema.data
                )
            if channel.id not in channels:
                channels[channel.id] = writer.register_channel(
                    channel.topic,
                    channel.message_encoding,
                    schemas.get(channel.schema_id, 0),
                    channel.metadata,
                )
            writer.add_message(
                channels[channel.id],
                message.log_time,
                message.data,
                message.publish_time,
                message.sequence,
            )
        names = []
        for attachment in reader.iter_attachments():
            names.append(attachment.name)
            writer.add_attachment(
                attachment.create_time,
                attachment.log_time,
                attachment.name,
                attachment.media_type,
                data if attachment.name == name else attachment.data,
            )
        assert name in names
        for metadata in reader.iter_metadata():
            writer.add_metadata(metadata.name, metadata.metadata)
        writer.finish()
    return target


@pytest.fixture(scope="module")
def flight(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return record(tmp_path_factory.mktemp("tamper") / "flight.mcap", APPENDIX_C)


BAD_YAML = b"limits:\n  max_speed: [oops\n"


@pytest.mark.parametrize(
    ("attachment", "message"),
    [
        ("world.yaml", "attachment world.yaml:3:1: invalid YAML: "),
        ("catalog.yaml", "attachment catalog.yaml:3:1: invalid YAML: "),
    ],
)
def test_replay_names_the_recording_and_the_attachment(
    flight: Path, tmp_path: Path, attachment: str, message: str
) -> None:
    path = tampered(flight, tmp_path / "tampered.mcap", attachment, BAD_YAML)
    result = runner.invoke(app, ["replay", str(path)])
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith(f"{path}: error: {message}"), lines[0]
    assert "default" not in lines[0]


def test_a_world_that_is_valid_yaml_but_wrong_is_marked_in_the_attachment(
    flight: Path, tmp_path: Path
) -> None:
    path = tampered(flight, tmp_path / "tampered.mcap", "world.yaml", b"limits: 7\n")
    result = runner.invoke(app, ["replay", str(path), "--format", "json"])
    assert result.exit_code == 2
    (entry,) = json.loads(result.stdout)["recordings"]
    assert entry["error"].startswith("attachment world.yaml:1:"), entry["error"]


def test_view_notes_the_recording_and_the_attachment(flight: Path, tmp_path: Path) -> None:
    path = tampered(flight, tmp_path / "tampered.mcap", "world.yaml", BAD_YAML)
    result = runner.invoke(app, ["view", str(path), "--output", str(tmp_path / "v.rrd")])
    assert result.exit_code == 0  # the markers are an extra: the view is still written
    notes = [x for x in result.stderr.splitlines() if "world.yaml" in x]
    assert notes and f"({path}#world.yaml:3:1: error: invalid YAML" in notes[0], notes
