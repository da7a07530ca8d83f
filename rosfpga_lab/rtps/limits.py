"""Limits and defaults of the rtps layer, in one place."""

from __future__ import annotations

#: Largest sample :class:`FragmentAssembler` puts together, and most samples it holds at once.
MAX_SAMPLE_BYTES = 64 * 1024 * 1024
MAX_PENDING_SAMPLES = 16
#: Bytes all partly reassembled samples of one assembler may hold together (fragments received).
MAX_PENDING_BYTES = 64 * 1024 * 1024

# ---- the participant (rosfpga_lab.rtps.participant) ----
#: RTPS port mapping (RTPS 2.3, 9.6.1.1): PB + DG * domain + offset + PG * index.
PORT_BASE, DOMAIN_GAIN, PARTICIPANT_GAIN = 7400, 250, 2
OFFSET_DISCOVERY_UNICAST, OFFSET_USER_UNICAST = 10, 11
#: ... the SPDP multicast port's offset (d0) and its group (RTPS 2.3 9.6.1.4.1: the default
#: multicast locator); a loopback graph has no multicast and probes the unicast ports instead.
OFFSET_DISCOVERY_MULTICAST = 0
SPDP_MULTICAST_ADDRESS = "239.255.0.1"
#: Largest domain id whose ports still fit in 16 bits (7400 + 250 * 232 + 11 + 2 * 119 < 65536).
MAX_DOMAIN_ID = 232
#: Participant indices probed (and tried when binding), as Cyclone DDS's MaxAutoParticipantIndex.
MAX_PARTICIPANT_INDEX = 9
#: Largest datagram the participant sends, and the DATA_FRAG fragment size (Cyclone DDS defaults).
MAX_MESSAGE_BYTES = 14720
FRAGMENT_BYTES = 1344
#: Lease the lab announces, period of its SPDP announcements, and the longest lease it believes.
LEASE_SECONDS = 10.0
ANNOUNCE_SECONDS = 1.0
MAX_LEASE_SECONDS = 300.0
#: ... the shortest one it believes, and the lease of a peer that announces none (RTPS's default
#: PID_PARTICIPANT_LEASE_DURATION, as Cyclone DDS takes it).
MIN_LEASE_SECONDS = 0.1
DEFAULT_LEASE_SECONDS = 100.0
#: Period of a reliable writer's HEARTBEATs while a reader has not acknowledged everything.
HEARTBEAT_SECONDS = 0.05
#: ... doubling while the reader does not answer, up to this (readers that are gone or fake).
MAX_HEARTBEAT_SECONDS = 1.0
#: A reader proxy's retransmissions are at least this far apart (ACKNACK and NACK_FRAG storms;
#: an ACKNACK's and each sample's NACK_FRAG's are paced apart).
MIN_RESEND_SECONDS = 0.005
#: A sample is not sent to one reader again within this of its last sending (written or
#: resent): RTPS's nackSuppressionDuration. A reader that lost it asks again at the next
#: HEARTBEAT; ACKNACKs in its name cannot pull a sample while it is on its way (each sample at
#: most once per heartbeat period per reader).
NACK_SUPPRESSION_SECONDS = 0.05
#: The resend budget of a reader proxy (rosfpga_lab.rtps.writer_side): what ACKNACKs and
#: NACK_FRAGs make a writer send again, over any time, is at most this many bytes per byte it
#: wrote to the history since the reader matched, plus the history's bytes at that time (the
#: budget starts at those and never holds more than this many histories). Four, not one: a
#: single large sample whose fragments a loaded receiver drops round after round (rclpy on Fast
#: DDS taking a 1.2 MB image on two busy cores) needs more than one copy resent, and a budget of
#: one left it incomplete for good. A sample the reader already
#: acknowledged is never resent to it (a GAP says so), so a storm of ACKNACKs in the real
#: reader's name gets GAPs, a few bytes per ACKNACK, and a fake reader that never acknowledges
#: gets at most this share of the stream it is sent anyway.
RESEND_PER_BYTE_WRITTEN = 4.0
#: Remote participants and endpoints the participant keeps (SPDP/SEDP floods; a full
#: participant table makes room for each new one: rosfpga_lab.rtps.spdp says which goes).
MAX_REMOTE_PARTICIPANTS = 64
MAX_REMOTE_ENDPOINTS = 512
#: A goodbye (SPDP dispose) from a source that is neither where the participant's first SPDP came
#: from nor one of its locators is suspect: its lease becomes this (its traffic keeps it alive).
#: One from there forgets it, and traffic from it later than GOODBYE_GRACE_SECONDS after the
#: goodbye learns it again (rosfpga_lab.rtps.spdp).
SUSPECT_GOODBYE_LEASE_SECONDS = 1.0
GOODBYE_GRACE_SECONDS = 0.1
#: Out-of-order samples a reliable reader holds per remote writer, and in bytes.
MAX_OUT_OF_ORDER = 64
MAX_OUT_OF_ORDER_BYTES = 32 * 1024 * 1024
#: Received samples kept for the application per reader beyond its history depth (never more),
#: and the deepest history a writer keeps (KEEP_LAST).
MAX_HISTORY_DEPTH = 1000
#: Bytes a writer's history holds at most: past them the oldest samples go before KEEP_LAST
#: depth says (one sample always stays). With MAX_HISTORY_DEPTH, what bounds a writer whatever
#: its readers do: the lab's writer is KEEP_LAST and never blocks; a RELIABLE reader, KEEP_ALL
#: included (history kind is not requested-vs-offered), that consumes slowly or never
#: acknowledges is sent each sample once, resent within its budget, and GAPped what left the
#: history (rosfpga_lab.rtps.writer_side); nothing is buffered per reader.
MAX_HISTORY_BYTES = 64 * 1024 * 1024
#: Distinct log notes kept (each is logged once).
MAX_NOTES = 256
#: Remote endpoints one local writer or reader is matched with (a writer sends each sample to
#: every matched reader: fake readers must not multiply a frame without bound).
MAX_MATCHED_PER_ENDPOINT = 32
