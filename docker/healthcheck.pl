#!/usr/bin/perl
# healthcheck.pl — the image's HEALTHCHECK (docker/Dockerfile), run by the engine inside the
# container as `perl healthcheck.pl`, with no shell and nothing but perl-base.
# Finds the `tessera serve` process of the container, takes the address and port from its
# --bind and --port (defaults 127.0.0.1 and 8080, as tessera's; 0.0.0.0 and :: are asked on
# loopback) and sends GET /healthz: exit 0 on a 200 answer within 4 s, 1 otherwise, with one
# line saying why. A container that runs no server (a farm render or merge) exits 0: such a
# task has no endpoint to ask, and it is alive while its process is.
use strict;
use warnings;
use IO::Socket::IP;

my @serve;
for my $file (glob "/proc/[0-9]*/cmdline") {
    open(my $fh, "<", $file) or next;
    local $/;
    my @argv = split /\0/, (<$fh> // "");
    if (@argv >= 2 && $argv[0] =~ m{(?:^|/)tessera$} && $argv[1] eq "serve") {
        @serve = @argv[2 .. $#argv];
        last;
    }
}
unless (@serve) {
    print "no tessera serve in this container: nothing to ask\n";
    exit 0;
}

my ($host, $port) = ("127.0.0.1", 8080);
for (my $i = 0; $i < @serve; $i++) {
    my ($name, $value) = $serve[$i] =~ /^--(bind|port)(?:=(.*))?$/ or next;
    $value = $serve[++$i] unless defined $value;
    last unless defined $value;
    if ($name eq "bind") { $host = $value } else { $port = $value }
}
$host = "127.0.0.1" if $host eq "0.0.0.0";
$host = "::1" if $host eq "::";
if ($port !~ /^[0-9]+$/ || $port == 0) {
    print "tessera serve --port '$port': no fixed port to ask\n";
    exit 1;
}

my $status = eval {
    local $SIG{ALRM} = sub { die "no answer within 4 s\n" };
    alarm 4;
    my $sock = IO::Socket::IP->new(PeerHost => $host, PeerPort => $port, Timeout => 3)
        or die "cannot connect to $host port $port: $@\n";
    # Host: the address asked, which the server answers for whatever it is bound to.
    my $authority = ($host =~ /:/ ? "[$host]" : $host) . ":$port";
    print $sock "GET /healthz HTTP/1.0\r\nHost: $authority\r\nConnection: close\r\n\r\n";
    my $line = <$sock> // die "connection closed without an answer\n";
    alarm 0;
    $line =~ s/\r?\n$//;
    $line;
};
if (!defined $status) {
    print "http://$host:$port/healthz: $@";
    exit 1;
}
print "http://$host:$port/healthz: $status\n";
exit($status =~ m{^HTTP/1\.[01] 200 } ? 0 : 1);
